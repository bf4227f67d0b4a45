#include "eval/evaluation.h"

#include <spdlog/spdlog.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>

#include "core/error.h"
#include "core/image_io.h"
#include "core/progress.h"
#include "core/text.h"
#include "eval/temporal.h"
#include "render_data/edges.h"
#include "render_data/patch_sampler.h"

namespace cgsr {

config::Schema<EvalOptions> eval_schema_fields() {
  config::Schema<EvalOptions> s;
  s.field("split", &EvalOptions::split, "data set split").one_of({"train", "val", "test", "all"});
  s.field("max_frames", &EvalOptions::max_frames, "frames to evaluate (0 = the whole split)").at_least(0);
  s.field("frames", &EvalOptions::frames, "frame index range A:B (A included, B not) within the split; empty = all")
      .check([](const std::string& v) { return v.empty() || parse_frame_range(v).has_value(); },
             "must be A:B with whole numbers 0 <= A < B");
  s.field("crop_border", &EvalOptions::crop_border, "HR pixels ignored at each border").range(0, 64);
  s.field("y_channel", &EvalOptions::y_channel, "PSNR/SSIM on BT.601 luma instead of RGB");
  s.field("temporal", &EvalOptions::temporal, "warping error between consecutive outputs");
  s.field("latency_runs", &EvalOptions::latency_runs, "timed runs for the latency column (0 = skip)").range(0, 1000);
  s.field("save_frames", &EvalOptions::save_frames, "directory for the upscaled frames (PNG); empty = none");
  return s;
}

std::vector<int> evaluation_frames(const Dataset& data, const EvalOptions& options) {
  std::vector<int> frames = data.frames(split_from_name(options.split));
  if (!options.frames.empty()) {
    const auto range = parse_frame_range(options.frames);
    if (!range) throw Error("eval.frames", "'" + options.frames + "' is not a range A:B with 0 <= A < B");
    std::vector<int> inside;
    for (int f : frames)
      if (f >= range->first && f < range->second) inside.push_back(f);
    if (inside.empty())
      throw Error(data.info().root.string(), "split '" + options.split + "' has no frame in " + options.frames);
    frames = inside;
  }
  if (frames.empty()) throw Error(data.info().root.string(), "split '" + options.split + "' has no frames");
  if (options.max_frames > 0 && static_cast<size_t>(options.max_frames) < frames.size()) {
    std::vector<int> picked;
    for (int i = 0; i < options.max_frames; ++i) picked.push_back(frames[i * frames.size() / options.max_frames]);
    frames = picked;
  }
  return frames;
}

namespace {
std::vector<RenderChannel> with_motion(std::vector<RenderChannel> channels) {
  if (std::find(channels.begin(), channels.end(), RenderChannel::Motion) == channels.end())
    channels.push_back(RenderChannel::Motion);
  std::sort(channels.begin(), channels.end());
  return channels;
}

bool carries(const Dataset& data, size_t resolution, RenderChannel channel) {
  const auto& here = channels_at(data.info(), resolution);
  return std::find(here.begin(), here.end(), channel) != here.end();
}

// Motion vectors at HR for the temporal error: the batch's own, or, for captures that store them
// at the render (LR) size only, the LR ones repeated over each s x s block and scaled by s.
torch::Tensor hr_motion(const Batch& b, const Dataset& data, int frame, size_t lr_resolution, int scale) {
  int offset = 0;
  for (auto c : b.channels) {
    if (c == RenderChannel::Motion) return b.hr_info.slice(1, offset, offset + channel_width(c));
    offset += channel_width(c);
  }
  return upsample_channel(data.frame(frame, lr_resolution)->motion.unsqueeze(0), RenderChannel::Motion, scale);
}

// The HR edge map of `frame` at the size of `hr_color` (the batch's HR frame, from the cache),
// or undefined when the dataset does not carry edges at that resolution.
torch::Tensor hr_edges(const Dataset& data, int frame, const torch::Tensor& hr_color) {
  const size_t resolution =
      data.resolution_index({static_cast<int>(hr_color.size(-1)), static_cast<int>(hr_color.size(-2))});
  return carries(data, resolution, RenderChannel::Edge) ? data.frame(frame, resolution)->edge : torch::Tensor();
}

// Mean of a per-frame PSNR over the frames that have one, infinite ones (no error) left out as
// in the overall PSNR; +inf when every one is infinite.
std::optional<double> mean_psnr(const std::vector<FrameScore>& frames, std::optional<double> FrameScore::*field) {
  double sum = 0;
  int finite = 0, present = 0;
  for (const auto& f : frames)
    if (f.*field) {
      ++present;
      if (!std::isinf(*(f.*field))) {
        sum += *(f.*field);
        ++finite;
      }
    }
  if (!present) return std::nullopt;
  return finite ? sum / finite : INFINITY;
}

std::string psnr_text(std::optional<double> value) {
  return value ? fmt::format("{:.3f} dB", *value) : std::string("n/a");
}

std::optional<double> mean_of(const std::vector<FrameScore>& frames, std::optional<double> FrameScore::*field) {
  double sum = 0;
  int n = 0;
  for (const auto& f : frames)
    if (f.*field) {
      sum += *(f.*field);
      ++n;
    }
  return n ? std::optional<double>(sum / n) : std::nullopt;
}
}  // namespace

torch::Tensor TimingSequence::run(Upscaler& upscaler, size_t i) const {
  if (!previous.empty()) {
    if (previous.at(i).lr_color.defined())
      upscaler.previous_frame(previous.at(i));
    else
      upscaler.reset_history();
  }
  return upscaler.upscale(frames.at(i));
}

TimingSequence timing_sequence(const Dataset& data, const std::vector<int>& frames, int scale,
                               const Upscaler& upscaler, int count) {
  constexpr int kMaxFrames = 16;  // frames held in memory (a 1080p batch is tens of MB)
  const auto channels = upscaler.channels();
  const DepthEncoding depth = upscaler.depth_encoding();
  TimingSequence out;
  // Spread over the frames, so that a model whose cost depends on the frame is timed on a fair
  // share of easy and hard ones.
  for (int f : spread_frames(frames, std::min(kMaxFrames, std::max(1, count)))) {
    out.frames.push_back(frame_batch(data, f, scale, channels, depth));
    if (upscaler.uses_previous_frame())
      out.previous.push_back(data.has_previous(f) ? frame_batch(data, f - 1, scale, channels, depth) : Batch{});
  }
  return out;
}

torch::Tensor run_up_to(Upscaler& upscaler, const Dataset& data, int frame, int scale,
                        const std::vector<RenderChannel>& channels, DepthEncoding depth, int& last_run) {
  const SceneInfo& scene = data.scene_of(frame);
  const bool continues = last_run >= scene.first_frame && last_run < frame;
  if (!continues) upscaler.reset_history();
  torch::Tensor before;
  for (int f = continues ? last_run + 1 : scene.first_frame; f < frame; ++f)
    before = upscaler.upscale(frame_batch(data, f, scale, channels, depth)).clamp(0.0, 1.0);
  last_run = frame;
  return before;
}

EvalResult evaluate(Upscaler& upscaler, const Dataset& data, const EvalOptions& options,
                    const std::function<void(const EvalResult&)>& on_quality) {
  if (upscaler.reads_bsp_border() && !data.info().bsp_border)
    throw Error(data.info().root.string(), upscaler.name() + " reads sub-pixel BSP border files, which this data set does "
                                           "not have: render it with bsp_border: {depth: 2} (docs/bsp_border.md)");
  EvalResult result;
  result.name = upscaler.name();
  result.precision = upscaler.precision();
  result.dataset = data.info().name;
  result.target = data.info().target;
  result.split = options.split;
  result.scale = upscaler.scale();
  const auto [lr_resolution, hr_resolution] = resolution_pair(data, result.scale);
  const bool hr_has_motion = carries(data, hr_resolution, RenderChannel::Motion);
  const bool temporal = options.temporal && (hr_has_motion || carries(data, lr_resolution, RenderChannel::Motion));
  if (options.temporal && !temporal)
    spdlog::warn("{}: no motion vectors, temporal error skipped", data.info().root.string());
  const auto channels = temporal && hr_has_motion ? with_motion(upscaler.channels()) : upscaler.channels();
  const DepthEncoding depth = upscaler.depth_encoding();
  QualityOptions quality;
  quality.crop_border = options.crop_border;
  quality.y_channel = options.y_channel;
  if (!options.save_frames.empty()) std::filesystem::create_directories(options.save_frames);

  const auto frames = evaluation_frames(data, options);
  for (const auto& scene : data.scenes())
    if (std::any_of(frames.begin(), frames.end(), [&](int f) { return scene.contains(f); }))
      result.scene_starts.push_back({scene.name, scene.first_frame});
  Progress progress("eval " + result.name, static_cast<int64_t>(frames.size()));
  double psnr_sum = 0, ssim_sum = 0;
  int psnr_count = 0;
  // A recurrent upscaler runs the frames of the scene up to `frame` first; the frame before's
  // output is kept for the temporal error.
  int last_run = -1;
  torch::Tensor run_before;
  // Shows a stateful upscaler the frame before `frame` first (see Upscaler::uses_previous_frame).
  const auto upscale_frame = [&](const Batch& b, int frame) {
    if (upscaler.recurrent()) run_before = run_up_to(upscaler, data, frame, result.scale, channels, depth, last_run);
    if (upscaler.uses_previous_frame()) {
      if (data.has_previous(frame))
        upscaler.previous_frame(frame_batch(data, frame - 1, result.scale, channels, depth));
      else
        upscaler.reset_history();
    }
    return upscaler.upscale(b);
  };
  // The last evaluated frame and its output: consecutive frames (a range) reuse it as the
  // previous output of the temporal error instead of upscaling that frame again.
  int last_frame = -1;
  Batch last_batch;
  torch::Tensor last_sr;
  bool warned_no_edges = false;
  for (int frame : frames) {
    const Batch b = frame_batch(data, frame, result.scale, channels, depth);
    const auto raw = upscale_frame(b, frame);
    const auto choice = upscaler.frame_choice();
    // Checked before clamping, which would turn infinite values into 0 and 1.
    if (!torch::isfinite(raw).all().item<bool>())
      throw Error(result.name + ": frame " + std::to_string(frame), "the upscaler produced NaN or infinite values");
    const auto sr = raw.clamp(0.0, 1.0);
    FrameScore score;
    score.frame = frame;
    score.choice = choice;
    score.psnr = psnr(sr, b.hr_color, quality).item<double>();
    score.ssim = ssim(sr, b.hr_color, quality).item<double>();
    if (std::isinf(score.psnr)) {
      ++result.identical_frames;
    } else {
      psnr_sum += score.psnr;
      ++psnr_count;
    }
    ssim_sum += score.ssim;
    if (const auto edges = hr_edges(data, frame, b.hr_color); edges.defined()) {
      const MaskedPsnr split = masked_psnr(sr, b.hr_color, dilate_edges(edges), quality).at(0);
      score.psnr_edge = split.inside;
      score.psnr_rest = split.outside;
      score.edge_fraction = split.inside_fraction;
    } else if (!warned_no_edges) {
      spdlog::warn("{}: no edge channel at {}x{}: PSNR on edges and on the rest skipped", data.info().root.string(),
                   b.hr_color.size(-1), b.hr_color.size(-2));
      warned_no_edges = true;
    }
    if (temporal && data.has_previous(frame)) {  // a scene's first frame has no predecessor
      const bool consecutive = last_frame == frame - 1;
      const Batch prev = consecutive ? last_batch : frame_batch(data, frame - 1, result.scale, channels, depth);
      const auto prev_sr = consecutive                  ? last_sr
                           : upscaler.recurrent()       ? run_before
                                                        : upscale_frame(prev, frame - 1).clamp(0.0, 1.0);
      const auto motion = hr_motion(b, data, frame, lr_resolution, result.scale);
      score.temporal_error = warping_error(sr, prev_sr, motion);
      score.temporal_error_reference = warping_error(b.hr_color, prev.hr_color, motion);
    }
    if (!options.save_frames.empty()) {
      char name[64];
      std::snprintf(name, sizeof name, "frame%04d.png", frame);
      write_image(std::filesystem::path(options.save_frames) / (result.name + "_" + name), sr[0]);
    }
    result.frames.push_back(score);
    last_frame = frame;
    last_batch = b;
    last_sr = sr;
    progress.advance();
  }
  progress.finish();
  result.psnr = psnr_count ? psnr_sum / psnr_count : INFINITY;
  result.ssim = ssim_sum / static_cast<double>(frames.size());
  result.psnr_edge = mean_psnr(result.frames, &FrameScore::psnr_edge);
  result.psnr_rest = mean_psnr(result.frames, &FrameScore::psnr_rest);
  result.edge_fraction = mean_of(result.frames, &FrameScore::edge_fraction);
  result.temporal_error = mean_of(result.frames, &FrameScore::temporal_error);
  result.temporal_error_reference = mean_of(result.frames, &FrameScore::temporal_error_reference);
  // Quality is known before latency, which can take minutes at large sizes.
  spdlog::info("{}: PSNR {:.3f} dB, SSIM {:.4f} on {} frame(s)", result.name, result.psnr, result.ssim, frames.size());
  if (result.edge_fraction)
    spdlog::info("{}: PSNR on geometry edges {} ({:.1f}% of pixels), on the rest {}", result.name,
                 psnr_text(result.psnr_edge), 100.0 * *result.edge_fraction, psnr_text(result.psnr_rest));

  const Batch first = frame_batch(data, frames.front(), result.scale, upscaler.channels(), upscaler.depth_encoding());
  result.lr_width = first.lr_color.size(3);
  result.lr_height = first.lr_color.size(2);
  result.cost = upscaler.cost(result.lr_width, result.lr_height);
  if (on_quality) on_quality(result);
  if (options.latency_runs > 0) {
    // Timed on the evaluated frames in turn, as a renderer calls it: an upscaler whose work
    // depends on the frame (a hybrid-pruned model) is timed on what it chooses per frame.
    const TimingSequence sequence = timing_sequence(data, frames, result.scale, upscaler, options.latency_runs);
    constexpr int kWarmup = 2;
    Progress timing("latency " + result.name, kWarmup + options.latency_runs);
    size_t next = 0;
    result.latency = measure_latency(
        [&] {
          sequence.run(upscaler, next++ % sequence.size());
          timing.advance();
        },
        kWarmup, options.latency_runs);
    timing.finish();
  }
  return result;
}

std::vector<SceneScore> scene_scores(const EvalResult& result, const Dataset& data) {
  std::vector<SceneScore> out;
  for (const auto& scene : data.scenes()) {
    SceneScore s;
    s.scene = scene.name;
    int finite = 0;
    for (const auto& f : result.frames) {
      if (!scene.contains(f.frame)) continue;
      ++s.frames;
      s.ssim += f.ssim;
      if (std::isinf(f.psnr)) {
        ++s.identical_frames;
      } else {
        s.psnr += f.psnr;
        ++finite;
      }
    }
    if (s.frames == 0) continue;
    s.ssim /= s.frames;
    s.psnr = finite ? s.psnr / finite : INFINITY;
    out.push_back(s);
  }
  return out;
}

namespace {
// Optional PSNRs: absent is null, infinite is null with "<key>_infinite": true (put_psnr).
void put_optional_psnr(nlohmann::ordered_json& j, const std::string& key, std::optional<double> value) {
  if (value)
    put_psnr(j, key, *value);
  else
    j[key] = nullptr;
}

std::optional<double> optional_psnr(const nlohmann::ordered_json& j, const std::string& key) {
  if (!j.contains(key)) return std::nullopt;  // written before edge PSNR existed
  if (!j.at(key).is_null()) return j.at(key).get<double>();
  if (j.value(key + "_infinite", false)) return INFINITY;
  return std::nullopt;
}

nlohmann::ordered_json optional_value(std::optional<double> value) {
  return value ? nlohmann::ordered_json(*value) : nullptr;
}

std::optional<double> optional_number(const nlohmann::ordered_json& j, const std::string& key) {
  if (!j.contains(key) || j.at(key).is_null()) return std::nullopt;
  return j.at(key).get<double>();
}

void put_edge_scores(nlohmann::ordered_json& j, std::optional<double> psnr_edge, std::optional<double> psnr_rest,
                     std::optional<double> edge_fraction) {
  put_optional_psnr(j, "psnr_edge", psnr_edge);
  put_optional_psnr(j, "psnr_rest", psnr_rest);
  j["edge_fraction"] = optional_value(edge_fraction);
}

// A frame's pattern choice in results files, under the key "details" it has always had there
// (files written before it was typed read the same).
nlohmann::ordered_json choice_json(const PatternChoice& c) {
  return {{"previous_frame", c.previous_frame},
          {"pattern", c.pattern},
          {"channel_fraction", c.channel_fraction},
          {"choose_ms", c.choose_ms}};
}

std::optional<PatternChoice> choice_from_json(const nlohmann::ordered_json& details) {
  if (!details.is_object() || !details.contains("pattern")) return std::nullopt;
  PatternChoice c;
  c.pattern = details.at("pattern").get<int>();
  c.channel_fraction = details.value("channel_fraction", 1.0);
  c.previous_frame = details.value("previous_frame", false);
  c.choose_ms = details.value("choose_ms", 0.0);
  return c;
}

std::string csv_psnr(std::optional<double> value) {
  if (!value) return "";
  return std::isinf(*value) ? std::string("inf") : std::to_string(*value);
}
}  // namespace

nlohmann::ordered_json to_json(const EvalResult& r) {
  nlohmann::ordered_json j;
  j["name"] = r.name;
  if (r.precision != Precision::Fp32) j["precision"] = enum_name(r.precision);
  j["dataset"] = r.dataset;
  j["target"] = r.target;
  j["split"] = r.split;
  j["scale"] = r.scale;
  j["lr_width"] = r.lr_width;
  j["lr_height"] = r.lr_height;
  put_psnr(j, "psnr", r.psnr);
  j["ssim"] = r.ssim;
  j["identical_frames"] = r.identical_frames;
  put_edge_scores(j, r.psnr_edge, r.psnr_rest, r.edge_fraction);
  j["temporal_error"] = r.temporal_error ? nlohmann::ordered_json(*r.temporal_error) : nullptr;
  j["temporal_error_reference"] =
      r.temporal_error_reference ? nlohmann::ordered_json(*r.temporal_error_reference) : nullptr;
  const auto latency_json = [](const LatencyStats& l) {
    return nlohmann::ordered_json{{"median", l.median_ms}, {"mean", l.mean_ms}, {"p95", l.p95_ms},
                                  {"min", l.min_ms},       {"max", l.max_ms},   {"runs", l.runs}};
  };
  j["latency_ms"] = r.latency ? latency_json(*r.latency) : nullptr;
  if (r.onnxruntime_latency) j["onnxruntime_latency_ms"] = latency_json(*r.onnxruntime_latency);
  if (r.cost) {
    j["params"] = r.cost->params;
    j["macs"] = r.cost->macs;
  } else {
    j["params"] = nullptr;
    j["macs"] = nullptr;
  }
  j["scene_starts"] = nlohmann::ordered_json::array();
  for (const auto& s : r.scene_starts) j["scene_starts"].push_back({{"scene", s.scene}, {"first_frame", s.first_frame}});
  j["frames"] = nlohmann::ordered_json::array();
  for (const auto& f : r.frames) {
    nlohmann::ordered_json fj;
    fj["frame"] = f.frame;
    put_psnr(fj, "psnr", f.psnr);
    fj["ssim"] = f.ssim;
    put_edge_scores(fj, f.psnr_edge, f.psnr_rest, f.edge_fraction);
    fj["temporal_error"] = f.temporal_error ? nlohmann::ordered_json(*f.temporal_error) : nullptr;
    fj["temporal_error_reference"] =
        f.temporal_error_reference ? nlohmann::ordered_json(*f.temporal_error_reference) : nullptr;
    if (f.choice) fj["details"] = choice_json(*f.choice);
    j["frames"].push_back(fj);
  }
  return j;
}

EvalResult eval_result_from_json(const nlohmann::ordered_json& j, const std::string& context) {
  try {
    EvalResult r;
    r.name = j.at("name");
    if (j.contains("precision")) r.precision = enum_from_name<Precision>(j.at("precision").get<std::string>());
    r.dataset = j.at("dataset");
    r.target = j.value("target", "");  // results from before the field
    r.split = j.at("split");
    r.scale = j.at("scale");
    r.lr_width = j.at("lr_width");
    r.lr_height = j.at("lr_height");
    r.psnr = j.at("psnr").is_null() ? INFINITY : j.at("psnr").get<double>();
    r.ssim = j.at("ssim");
    r.identical_frames = j.value("identical_frames", 0);
    r.psnr_edge = optional_psnr(j, "psnr_edge");
    r.psnr_rest = optional_psnr(j, "psnr_rest");
    r.edge_fraction = optional_number(j, "edge_fraction");
    if (!j.at("temporal_error").is_null()) r.temporal_error = j.at("temporal_error").get<double>();
    if (!j.at("temporal_error_reference").is_null())
      r.temporal_error_reference = j.at("temporal_error_reference").get<double>();
    const auto latency = [](const nlohmann::ordered_json& l) {
      LatencyStats stats;
      stats.median_ms = l.at("median");
      stats.min_ms = l.at("min");
      stats.max_ms = l.at("max");
      stats.mean_ms = l.value("mean", stats.median_ms);
      stats.p95_ms = l.value("p95", stats.max_ms);
      stats.runs = l.at("runs");
      return stats;
    };
    if (!j.at("latency_ms").is_null()) r.latency = latency(j["latency_ms"]);
    if (j.contains("onnxruntime_latency_ms")) r.onnxruntime_latency = latency(j["onnxruntime_latency_ms"]);
    if (!j.at("params").is_null()) {
      Complexity c;
      c.params = j.at("params");
      c.macs = j.at("macs");
      c.lr_width = r.lr_width;
      c.lr_height = r.lr_height;
      r.cost = c;
    }
    if (j.contains("scene_starts"))  // results from before the field: one scene
      for (const auto& s : j.at("scene_starts"))
        r.scene_starts.push_back({s.at("scene").get<std::string>(), s.at("first_frame").get<int>()});
    for (const auto& f : j.at("frames")) {
      FrameScore s;
      s.frame = f.at("frame");
      s.psnr = f.at("psnr").is_null() ? INFINITY : f.at("psnr").get<double>();
      s.ssim = f.at("ssim");
      s.psnr_edge = optional_psnr(f, "psnr_edge");
      s.psnr_rest = optional_psnr(f, "psnr_rest");
      s.edge_fraction = optional_number(f, "edge_fraction");
      if (!f.at("temporal_error").is_null()) s.temporal_error = f.at("temporal_error").get<double>();
      if (!f.at("temporal_error_reference").is_null())
        s.temporal_error_reference = f.at("temporal_error_reference").get<double>();
      if (f.contains("details")) s.choice = choice_from_json(f["details"]);
      r.frames.push_back(s);
    }
    return r;
  } catch (const nlohmann::json::exception& e) {
    throw Error(context, std::string("not an evaluation result: ") + e.what());
  }
}

std::string frames_csv(const EvalResult& r) {
  std::ostringstream csv;
  csv << "model,frame,psnr,ssim,temporal_error,temporal_error_reference,psnr_edge,psnr_rest,edge_fraction\n";
  for (const auto& f : r.frames) {
    csv << r.name << "," << f.frame << "," << (std::isinf(f.psnr) ? std::string("inf") : std::to_string(f.psnr)) << ","
        << f.ssim << "," << (f.temporal_error ? std::to_string(*f.temporal_error) : "") << ","
        << (f.temporal_error_reference ? std::to_string(*f.temporal_error_reference) : "") << ","
        << csv_psnr(f.psnr_edge) << "," << csv_psnr(f.psnr_rest) << ","
        << (f.edge_fraction ? std::to_string(*f.edge_fraction) : "") << "\n";
  }
  return csv.str();
}

}  // namespace cgsr
