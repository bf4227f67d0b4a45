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
//   color_alpha: ignore         # RGBA colour: ignore (drop alpha) or premultiplied
//   depth_encoding: normalized  # normalized, reversed, linear (x depth_scale) or linear_normalized
//   depth_scale: 1              # linear only: metres per stored unit (integer code or float)
//   motion_format:              # how motion images map to pixels (default: float (dx, dy))
//     x: {channels: [0, 1], scale: 2, offset: 0.5}   # [high, low] channels of a 16-bit code
//     y: {channels: [2, 3], scale: -2, offset: 0.5}
//     units: uv                 # pixels, or fractions of the frame's width and height
//   jitter: lr/jitter.txt       # the LR frames' sub-pixel jitter, one "x y" line per frame (default: none)
//   resolutions:
//     - size: 640x360
//       color: lr/color_*.png
//       depth: lr/depth_*.png
//       motion: lr/mv_*.png
//     - size: 1280x720
//       color: hr/frame_*.png
//
// Patterns are relative to the YAML file; wildcards (* and ?) only in the file name part. The
// encodings are capture_format.h's; docs/captures.md walks through a real capture.
// Other channels: normal ((n + 1) / 2 in an RGB image), normal_angle (grey), edge (grey, 0/1).
// The jitter file gives the smallest resolution's offset per frame in cgsr's convention (LR
// pixels in [-0.5, 0.5), the content at p + offset: render_data/jitter.h); blank lines and lines
// starting with '#' are skipped.

#include <filesystem>
#include <string>
#include <vector>

#include "core/config.h"
#include "render_data/capture_format.h"

namespace cgsr {

struct GlobResolution {
  std::string size;
  std::string color, depth, normal, normal_angle, edge, motion;
};

struct GlobLayoutOptions {
  std::string layout = "glob";
  std::string name;
  double near_plane = 0.1, far_plane = 1000, vfov = 60;
  ColorAlpha color_alpha = ColorAlpha::Ignore;
  CaptureDepth depth_encoding = CaptureDepth::Normalized;
  double depth_scale = 1;
  MotionFormat motion_format;
  std::string jitter;  // a text file of per-frame jitter offsets; empty: the frames are not jittered
  std::vector<GlobResolution> resolutions;
};

config::Schema<GlobLayoutOptions> glob_layout_schema();

// Files matching `pattern` (relative to `base`), in natural order.
std::vector<std::filesystem::path> glob_files(const std::filesystem::path& base, const std::string& pattern);
// "frame2" < "frame10".
bool natural_less(const std::string& a, const std::string& b);

}  // namespace cgsr
