#pragma once
// `cgsr data preview DIR --frame N --out FILE.png`: a montage of one frame, LR (pixels enlarged)
// beside HR, one row per channel (colour, depth, normals, edges, ...).

#include <CLI/CLI.hpp>

#include "cli/command.h"
#include "render_data/dataset.h"

namespace cgsr::cli {

struct DataPreviewOptions : RunSettings {
  std::string dir;       // dataset (positional)
  int frame = 0;
  std::string lr;        // LR resolution WxH; empty: the smallest
  std::string hr;        // HR resolution WxH; empty: the largest
  std::vector<std::string> channels = {"color", "depth", "normal", "edge"};
  std::string crop;      // "x,y,w,h" in HR pixels (multiples of the scale); empty: whole frame
  std::string image;     // output PNG
  DatasetOpenOptions open;
};

config::Schema<DataPreviewOptions> data_preview_schema();
void setup_data_preview(CLI::App& data);
nlohmann::ordered_json run_data_preview(const DataPreviewOptions& options);

}  // namespace cgsr::cli
