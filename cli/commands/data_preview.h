#pragma once
// `cgsr data preview DIR --frame N --out FILE.png`: a montage of one frame, LR (pixels enlarged)
// beside HR, one row per channel (colour, depth, normals, edges, ...). With `frames: [...]`, a
// grid of those frames instead (one channel, at one resolution): e.g. the scenes of a scene set.

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
  std::vector<int> frames;  // grid mode: these frames, `columns` per row, at `resolution`
  int columns = 4;
  std::string resolution;   // grid mode: WxH of the tiles; empty: the smallest
  DatasetOpenOptions open;
};

config::Schema<DataPreviewOptions> data_preview_schema();
void setup_data_preview(CLI::App& data);
nlohmann::ordered_json run_data_preview(const DataPreviewOptions& options);

}  // namespace cgsr::cli
