#pragma once
// The generic capture layout: a YAML file that lists, per resolution, a glob pattern per channel.
// Only colour is required; other channels are optional (missing ones can be derived, see
// dataset.h). Files of a pattern are sorted in natural order (numbers compared by value); the
// i-th file of every pattern is frame i, so every pattern must match the same number of files.
//
//   layout: glob
//   name: my_capture
//   near: 0.1                   # planes of the capture's depth
//   far: 1000
//   vfov: 60                    # vertical field of view (for derived normals)
//   depth_encoding: normalized  # normalized: z-buffer values in [0,1] (8/16-bit images), as
//                               #   normalize_depth; linear: view depth in metres (float EXR/TIFF,
//                               #   0 or inf = no geometry)
//   resolutions:
//     - size: 640x360
//       color: lr/color_*.png
//       depth: lr/depth_*.png
//       motion: lr/mv_*.exr     # first two channels: (dx, dy) in pixels, render_channels.h sign
//     - size: 1280x720
//       color: hr/frame_*.png
//
// Patterns are relative to the YAML file; wildcards (* and ?) only in the file name part.
// Other channels: normal ((n + 1) / 2 in an RGB image), normal_angle (grey), edge (grey, 0/1).

#include <filesystem>
#include <string>
#include <vector>

#include "core/config.h"

namespace cgsr {

struct GlobResolution {
  std::string size;
  std::string color, depth, normal, normal_angle, edge, motion;
};

struct GlobLayoutOptions {
  std::string layout = "glob";
  std::string name;
  double near_plane = 0.1, far_plane = 1000, vfov = 60;
  std::string depth_encoding = "normalized";
  std::vector<GlobResolution> resolutions;
};

config::Schema<GlobLayoutOptions> glob_layout_schema();

// Files matching `pattern` (relative to `base`), in natural order.
std::vector<std::filesystem::path> glob_files(const std::filesystem::path& base, const std::string& pattern);
// "frame2" < "frame10".
bool natural_less(const std::string& a, const std::string& b);

}  // namespace cgsr
