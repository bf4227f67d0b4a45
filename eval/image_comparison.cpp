#include "eval/image_comparison.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <spdlog/spdlog.h>

#include "core/canvas.h"
#include "core/error.h"
#include "core/metrics.h"
#include "core/text.h"
#include "render_data/patch_sampler.h"

namespace cgsr {

config::Schema<ComparisonOptions> comparison_schema_fields() {
  config::Schema<ComparisonOptions> s;
  s.field("frames", &ComparisonOptions::frames, "frames compared, those with the most geometry edges (0 = none)")
      .range(0, 16);
  s.field("crop", &ComparisonOptions::crop, "side of the square crop, HR pixels").range(16, 512);
  s.field("zoom", &ComparisonOptions::zoom, "each crop pixel drawn as zoom x zoom").range(1, 8);
  s.field("at", &ComparisonOptions::at, "[x, y]: the crop's top-left corner in HR pixels (empty: chosen)")
      .check([](const std::vector<int>& v) { return v.empty() || (v.size() == 2 && v[0] >= 0 && v[1] >= 0); },
             "must be empty or [x, y] with x, y >= 0");
  return s;
}

std::vector<int> frames_with_most_edges(const EvalResult& result, int count) {
  std::vector<const FrameScore*> frames;
  for (const auto& f : result.frames) frames.push_back(&f);
  std::stable_sort(frames.begin(), frames.end(), [](const FrameScore* a, const FrameScore* b) {
    return a->edge_fraction.value_or(0) > b->edge_fraction.value_or(0);
  });
  std::vector<int> out;
  for (size_t i = 0; i < frames.size() && static_cast<int>(i) < count; ++i) out.push_back(frames[i]->frame);
  return out;
}

namespace {
// [1, 3, H, W] -> [H, W] absolute difference averaged over the colour channels.
torch::Tensor abs_difference(const torch::Tensor& a, const torch::Tensor& b) {
  return (a.clamp(0, 1) - b.clamp(0, 1)).abs().mean(1)[0].contiguous();
}

cv::Mat to_mat(const torch::Tensor& hw) {
  return cv::Mat(static_cast<int>(hw.size(0)), static_cast<int>(hw.size(1)), CV_32F, hw.data_ptr<float>()).clone();
}

// [1, 3, H, W] in [0, 1] -> 8-bit BGR.
cv::Mat to_bgr(const torch::Tensor& image) {
  const torch::Tensor hwc =
      (image[0].clamp(0, 1) * 255.0).round().to(torch::kUInt8).flip(0).permute({1, 2, 0}).contiguous();
  return cv::Mat(static_cast<int>(hwc.size(0)), static_cast<int>(hwc.size(1)), CV_8UC3, hwc.data_ptr<uint8_t>()).clone();
}

cv::Mat zoomed(const cv::Mat& image, int zoom) {
  cv::Mat out;
  cv::resize(image, out, {}, zoom, zoom, cv::INTER_NEAREST);
  return out;
}

double crop_psnr(const torch::Tensor& output, const torch::Tensor& truth, const cv::Rect& r) {
  using torch::indexing::Slice;
  const auto crop = [&](const torch::Tensor& t) {
    return t.index({Slice(), Slice(), Slice(r.y, r.y + r.height), Slice(r.x, r.x + r.width)}).clamp(0, 1);
  };
  const double mse = (crop(output) - crop(truth)).pow(2).mean().item<double>();
  return mse > 0 ? 10.0 * std::log10(1.0 / mse) : std::numeric_limits<double>::infinity();
}

const TextStyle kName{12, true}, kFigure{11, false, {70, 70, 70}}, kHeading{14, true};

// Tiles in rows, each with its name and a figure under it; returns the canvas.
struct Tile {
  cv::Mat image;
  std::string name, figure;
};
std::unique_ptr<Canvas> tile_grid(const std::string& heading, const std::vector<Tile>& tiles, int columns,
                                  const cv::Mat& colour_bar = {}, const std::string& bar_low = "",
                                  const std::string& bar_high = "") {
  Canvas probe(1, 1);
  double column = 0, tile_h = 0;
  for (const auto& t : tiles) {
    column = std::max({column, double(t.image.cols), probe.measure(t.name, kName).width() + 8,
                       probe.measure(t.figure, kFigure).width() + 8});
    tile_h = std::max(tile_h, double(t.image.rows));
  }
  const double text_h = probe.measure("Ag", kName).height() + probe.measure("Ag", kFigure).height() + 10;
  const double head_h = probe.measure("Ag", kHeading).height() + 16, gap = 10;
  const int rows = (static_cast<int>(tiles.size()) + columns - 1) / columns;
  const double row_h = tile_h + text_h + gap;
  const double bar_h = colour_bar.empty() ? 0 : colour_bar.rows + probe.measure("Ag", kFigure).height() + 16;
  const double width = std::max(gap + columns * (column + gap), probe.measure(heading, kHeading).width() + 2 * gap);
  auto canvas = std::make_unique<Canvas>(static_cast<int>(std::ceil(width)),
                                         static_cast<int>(std::ceil(head_h + rows * row_h + bar_h + gap)));
  Canvas& c = *canvas;
  c.text({gap, head_h - 10}, heading, kHeading);
  for (size_t i = 0; i < tiles.size(); ++i) {
    const double x = gap + (i % columns) * (column + gap), y = head_h + (i / columns) * row_h;
    const double cx = x + column / 2;
    c.image({cx - tiles[i].image.cols / 2.0, y}, tiles[i].image);
    const double name_y = y + tile_h + probe.measure("Ag", kName).height();
    c.text({cx, name_y}, tiles[i].name, kName, Anchor::Centre);
    c.text({cx, name_y + probe.measure("Ag", kFigure).height() + 2}, tiles[i].figure, kFigure, Anchor::Centre);
  }
  if (!colour_bar.empty()) {
    const double y = head_h + rows * row_h + 4;
    c.image({gap, y}, colour_bar);
    const double ty = y + colour_bar.rows + probe.measure("Ag", kFigure).height() + 2;
    c.text({gap, ty}, bar_low, kFigure);
    c.text({gap + colour_bar.cols, ty}, bar_high, kFigure, Anchor::Right);
  }
  return canvas;
}

cv::Mat colour_bar(int width, int height) {
  cv::Mat ramp(1, width, CV_8U);
  for (int x = 0; x < width; ++x) ramp.at<uint8_t>(0, x) = static_cast<uint8_t>(std::lround(255.0 * x / (width - 1)));
  cv::Mat bar;
  cv::applyColorMap(cv::repeat(ramp, height, 1), bar, cv::COLORMAP_INFERNO);
  return bar;
}
}  // namespace

cv::Point choose_crop(const std::vector<torch::Tensor>& outputs, const torch::Tensor& reference,
                      const torch::Tensor& truth, int size) {
  const int h = static_cast<int>(reference.size(-2)), w = static_cast<int>(reference.size(-1));
  if (size > w || size > h || outputs.empty()) return {0, 0};
  const torch::Tensor reference_error = abs_difference(reference, truth);
  torch::Tensor difference = torch::zeros({h, w});
  for (const auto& o : outputs) difference += (reference_error - abs_difference(o, truth)).abs();
  cv::Mat integral;
  cv::integral(to_mat(difference), integral, CV_64F);
  const int step = std::max(1, size / 8);
  cv::Point best(0, 0);
  double best_sum = -1;
  for (int y = 0; y + size <= h; y += step)
    for (int x = 0; x + size <= w; x += step) {
      const double sum = integral.at<double>(y + size, x + size) - integral.at<double>(y, x + size) -
                         integral.at<double>(y + size, x) + integral.at<double>(y, x);
      if (sum > best_sum) {
        best_sum = sum;
        best = {x, y};
      }
    }
  return best;
}

double shared_error_scale(const std::vector<torch::Tensor>& outputs, const torch::Tensor& truth, const cv::Rect& r) {
  using torch::indexing::Slice;
  std::vector<torch::Tensor> errors;
  for (const auto& o : outputs)
    errors.push_back(abs_difference(o, truth).index({Slice(r.y, r.y + r.height), Slice(r.x, r.x + r.width)}).flatten());
  const torch::Tensor all = torch::cat(errors);
  const double q = torch::quantile(all, 0.99).item<double>();
  return std::max(q, 1.0 / 255.0);
}

cv::Mat error_map(const torch::Tensor& output, const torch::Tensor& truth, const cv::Rect& r, double scale) {
  const cv::Mat error = to_mat(abs_difference(output, truth))(r);
  cv::Mat levels, coloured;
  error.convertTo(levels, CV_8U, 255.0 / scale);  // saturates above the scale
  cv::applyColorMap(levels, coloured, cv::COLORMAP_INFERNO);
  return coloured;
}

nlohmann::ordered_json to_json(const ComparisonImage& image) {
  nlohmann::ordered_json psnr = nlohmann::ordered_json::array();
  for (const auto& [name, value] : image.crop_psnr)
    psnr.push_back({{"upscaler", name}, {"psnr", std::isfinite(value) ? nlohmann::ordered_json(value) : nullptr}});
  return {{"dataset", image.dataset},
          {"frame", image.frame},
          {"region", {image.region.x, image.region.y, image.region.width, image.region.height}},
          {"error_scale", image.error_scale},
          {"crops", image.crops},
          {"errors", image.errors},
          {"crop_psnr", psnr}};
}

ComparisonImage comparison_from_json(const nlohmann::ordered_json& j, const std::string& context) {
  try {
    ComparisonImage image;
    image.dataset = j.at("dataset").get<std::string>();
    image.frame = j.at("frame").get<int>();
    const auto r = j.at("region").get<std::vector<int>>();
    if (r.size() != 4) throw Error(context, "'region' needs [x, y, width, height]");
    image.region = {r[0], r[1], r[2], r[3]};
    image.error_scale = j.at("error_scale").get<double>();
    image.crops = j.at("crops").get<std::string>();
    image.errors = j.at("errors").get<std::string>();
    for (const auto& p : j.at("crop_psnr"))
      image.crop_psnr.emplace_back(p.at("upscaler").get<std::string>(), p.at("psnr").is_null()
                                                                            ? std::numeric_limits<double>::infinity()
                                                                            : p.at("psnr").get<double>());
    return image;
  } catch (const nlohmann::json::exception& e) {
    throw Error(context, std::string("not an image comparison: ") + e.what());
  }
}

ComparisonImage compare_frame(const std::vector<Upscaler*>& networks, const Dataset& data, int frame, int scale,
                              const ComparisonOptions& options, const std::filesystem::path& dir) {
  std::vector<std::unique_ptr<Upscaler>> classic;
  for (const char* name : {"nearest", "bicubic", "fsr"}) classic.push_back(classic_upscalers().get(name)(scale));
  std::vector<Upscaler*> all;
  for (auto& c : classic) all.push_back(c.get());
  all.insert(all.end(), networks.begin(), networks.end());

  std::vector<torch::Tensor> outputs;
  torch::Tensor truth;
  for (Upscaler* u : all) {
    const TimingSequence frame_only = timing_sequence(data, {frame}, scale, *u, 1);
    if (u->recurrent()) {  // its state at `frame`: the scene run up to it
      int last_run = -1;
      run_up_to(*u, data, frame, scale, u->channels(), u->depth_encoding(), last_run);
    }
    outputs.push_back(frame_only.run(*u, 0).detach().to(torch::kFloat32).contiguous());
    if (!truth.defined()) truth = frame_only.frames.front().hr_color.to(torch::kFloat32).contiguous();
    if (!torch::isfinite(outputs.back()).all().item<bool>())
      spdlog::warn("{} frame {}: {} gave non-finite values (drawn clamped)", data.info().name, frame, u->name());
    outputs.back() = torch::nan_to_num(outputs.back(), 0.0, 1.0, 0.0);
  }
  const int hr_w = static_cast<int>(truth.size(-1)), hr_h = static_cast<int>(truth.size(-2));
  const int size = std::min({options.crop, hr_w, hr_h});
  cv::Point corner;
  if (options.at.size() == 2) {
    corner = {std::min(options.at[0], hr_w - size), std::min(options.at[1], hr_h - size)};
  } else {
    // Where the networks' errors differ most from bicubic's (without networks: the other classic
    // upscalers').
    std::vector<torch::Tensor> others(outputs.begin() + (networks.empty() ? 0 : 3), outputs.end());
    corner = choose_crop(others, outputs[1], truth, size);
  }
  ComparisonImage image;
  image.dataset = data.info().name;
  image.frame = frame;
  image.region = {corner.x, corner.y, size, size};
  image.error_scale = shared_error_scale(outputs, truth, image.region);

  const std::string stem = data.info().name + "_frame" + std::to_string(frame);
  const std::string where = "x" + std::to_string(image.region.x) + " y" + std::to_string(image.region.y) + ", " +
                            std::to_string(size) + " px";
  std::vector<Tile> crops, errors;
  // The whole frame first, the region outlined, at the crops' size.
  cv::Mat overview = to_bgr(truth);
  cv::rectangle(overview, image.region, cv::Scalar(40, 40, 230), std::max(2, hr_w / 200));
  const int side = size * options.zoom;
  cv::resize(overview, overview, {side, side * hr_h / hr_w}, 0, 0, cv::INTER_AREA);
  crops.push_back({overview, "frame " + std::to_string(frame), where});
  for (size_t i = 0; i < all.size(); ++i) {
    const double psnr = crop_psnr(outputs[i], truth, image.region);
    image.crop_psnr.emplace_back(all[i]->name(), psnr);
    const std::string name = i == 0 ? "LR (nearest)" : all[i]->name();
    const std::string figure = fixed(psnr, 2) + " dB in the crop";
    crops.push_back({zoomed(to_bgr(outputs[i])(image.region), options.zoom), name, figure});
    errors.push_back({zoomed(error_map(outputs[i], truth, image.region, image.error_scale), options.zoom), name, figure});
  }
  crops.push_back({zoomed(to_bgr(truth)(image.region), options.zoom), "ground truth", "HR render"});

  const int columns = std::min<int>(5, static_cast<int>(crops.size()));
  image.crops = stem + "_crops.png";
  image.errors = stem + "_errors.png";
  tile_grid(data.info().name + ", frame " + std::to_string(frame) + ": the same crop of each upscaler's output",
            crops, columns)
      ->save(dir / image.crops);
  tile_grid(data.info().name + ", frame " + std::to_string(frame) + ": absolute error (colour channels averaged)",
            errors, columns, colour_bar(std::min(400, columns * side), 14), "0",
            fixed(image.error_scale, 3) + " and above")
      ->save(dir / image.errors);
  return image;
}

}  // namespace cgsr
