#include "cli/commands/data_preview.h"

#include <cstdio>

#include "core/error.h"
#include "core/image_io.h"
#include "render_data/visualize.h"

namespace cgsr::cli {

config::Schema<DataPreviewOptions> data_preview_schema() {
  config::Schema<DataPreviewOptions> s;
  s.field("dir", &DataPreviewOptions::dir, "dataset directory or glob-layout YAML file").required();
  s.field("frame", &DataPreviewOptions::frame, "frame index").at_least(0);
  s.field("lr", &DataPreviewOptions::lr, "LR resolution WxH (default: the smallest)");
  s.field("hr", &DataPreviewOptions::hr, "HR resolution WxH (default: the largest)");
  s.field("channels", &DataPreviewOptions::channels, "rows of the montage").one_of(preview_channel_names());
  s.field("crop", &DataPreviewOptions::crop, "x,y,w,h in HR pixels, multiples of the scale (default: whole frame)");
  s.field("image", &DataPreviewOptions::image, "output PNG file").required();
  s.field("frames", &DataPreviewOptions::frames, "a grid of these frames instead of one frame (first channel only)")
      .at_least(0);
  s.field("columns", &DataPreviewOptions::columns, "grid: frames per row").range(1, 64);
  s.field("resolution", &DataPreviewOptions::resolution, "grid: resolution WxH of the tiles (default: the smallest)");
  // One-frame previews resolve as before the grid existed.
  s.omit_when("frames", [](const DataPreviewOptions& o) { return o.frames.empty(); });
  s.omit_when("columns", [](const DataPreviewOptions& o) { return o.frames.empty(); });
  s.omit_when("resolution", [](const DataPreviewOptions& o) { return o.frames.empty(); });
  s.section("open", &DataPreviewOptions::open, dataset_open_schema(), "how to open the dataset");
  add_run_settings(s);
  return s;
}

void setup_data_preview(CLI::App& data) {
  add_command<DataPreviewOptions>(
      data, "preview", "Write a PNG montage of one frame: LR beside HR, one row per channel", data_preview_schema,
      [](CLI::App& sub, std::vector<FlagAssignment>& flags) {
        sub.add_option_function<std::string>(
            "dir", [&flags](const std::string& v) { flags.push_back({"dir=" + v, "DIR " + v}); },
            "dataset directory or glob-layout YAML file");
        flag_to_key(sub, flags, "--frame", "frame", "frame index");
        flag_to_key(sub, flags, "--image", "image", "output PNG file");
        flag_to_key(sub, flags, "--crop", "crop", "x,y,w,h in HR pixels");
        flag_to_key(sub, flags, "--channels", "channels", "rows, e.g. [color,depth,normal,edge]");
      },
      [](const DataPreviewOptions& options, const YAML::Node&, RunDir*) { return run_data_preview(options); },
      /*always_run_dir=*/false);
}

namespace {
torch::Tensor frame_grid(const Dataset& data, const DataPreviewOptions& options) {
  const size_t at = options.resolution.empty() ? 0 : data.resolution_index(parse_resolution(options.resolution, "resolution"));
  std::vector<Frame> frames;
  for (int f : options.frames) {
    if (f >= data.frame_count())
      throw Error(options.dir, "frame " + std::to_string(f) + " of 'frames' is beyond the data set's " +
                                   std::to_string(data.frame_count()) + " frames");
    frames.push_back(data.load(f, at));
  }
  return tile_frames(frames, preview_channel_from_name(options.channels.at(0)), options.columns);
}
}  // namespace

nlohmann::ordered_json run_data_preview(const DataPreviewOptions& options) {
  const Dataset data = Dataset::open(options.dir, options.open);
  if (!options.frames.empty()) {
    const auto image = frame_grid(data, options);
    write_image(options.image, image);
    std::printf("wrote %s (%zu frames, %lldx%lld)\n", options.image.c_str(), options.frames.size(),
                static_cast<long long>(image.size(2)), static_cast<long long>(image.size(1)));
    return {{"image", options.image}};
  }
  const auto& rs = data.resolutions();
  const size_t lo = options.lr.empty() ? 0 : data.resolution_index(parse_resolution(options.lr, "lr"));
  const size_t hi = options.hr.empty() ? rs.size() - 1 : data.resolution_index(parse_resolution(options.hr, "hr"));
  if (hi <= lo) throw Error(options.dir, "needs two resolutions, LR smaller than HR");
  Frame lr = data.load(options.frame, lo), hr = data.load(options.frame, hi);
  if (!options.crop.empty()) {
    int x, y, w, h;
    const int s = rs[hi].width / rs[lo].width;
    if (std::sscanf(options.crop.c_str(), "%d,%d,%d,%d", &x, &y, &w, &h) != 4 || x % s || y % s || w % s || h % s ||
        x < 0 || y < 0 || w <= 0 || h <= 0 || x + w > hr.width || y + h > hr.height)
      throw Error("crop", "expected x,y,w,h inside the HR frame, multiples of the scale " + std::to_string(s));
    hr = crop(hr, x, y, w, h);
    lr = crop(lr, x / s, y / s, w / s, h / s);
  }
  std::vector<PreviewChannel> rows;
  for (const auto& c : options.channels) rows.push_back(preview_channel_from_name(c));
  const auto image = montage(lr, hr, rows);
  write_image(options.image, image);
  std::printf("wrote %s (%lldx%lld)\n", options.image.c_str(), static_cast<long long>(image.size(2)),
              static_cast<long long>(image.size(1)));
  nlohmann::ordered_json j;
  j["image"] = options.image;
  return j;
}

}  // namespace cgsr::cli
