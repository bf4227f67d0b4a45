#pragma once
// How a game capture stores its channels, and the decoders from its images to cgsr's frame
// contract (frame.h). Used by the glob layout (glob_layout.h), whose YAML declares the formats.
//
//   colour  1 (grey), 3 (RGB) or 4 (RGBA) channels, 8/16-bit or float in [0,1] (display-referred:
//           tone-map HDR captures first). Alpha is dropped (`ignore`) or divided out of
//           premultiplied colour (`premultiplied`; pixels with alpha 0 become black).
//   depth   first channel, an encoding of view depth z:
//             normalized         z-buffer d in [0,1], 1/z linear in d from near (0) to far (1)
//             reversed           reversed z-buffer: 1 at near, 0 at far
//             linear             z = stored value x scale (an integer image's value is its code,
//                                0..255 or 0..65535; a float image's is the float)
//             linear_normalized  z = d x far, d in [0,1]
//           The clear value (normalized 1, reversed 0, linear 0 or inf, linear_normalized 0 or 1)
//           means no geometry (+inf). The decoder also says how precise the depth is
//           (edges.h DepthPrecision), so derived edges ignore quantisation staircases.
//   motion  (dx, dy) in pixels, render_channels.h's sign (a pixel at p was at p + motion in the
//           previous frame). Each component is one channel, or two channels holding the high and
//           low part of one code (RGBA-packed 16-bit motion in an 8-bit PNG). Its value is
//           (code / max code - offset) x scale for integer images, (value - offset) x scale for
//           float ones; `uv` units are fractions of the frame's width and height. A negative
//           scale flips a convention (motion to the next frame, y up).

#include <string>
#include <vector>

#include "core/config.h"
#include "core/image_io.h"
#include "render_data/edges.h"

namespace cgsr {

enum class ColorAlpha { Ignore, Premultiplied };
template <>
struct EnumNames<ColorAlpha> {
  static constexpr const char* kind = "color_alpha";
  static const std::vector<std::string>& names();  // ignore, premultiplied
};

enum class CaptureDepth { Normalized, Reversed, Linear, LinearNormalized };
template <>
struct EnumNames<CaptureDepth> {
  static constexpr const char* kind = "depth_encoding";
  static const std::vector<std::string>& names();  // normalized, reversed, linear, linear_normalized
};

enum class MotionUnits { Pixels, Uv };
template <>
struct EnumNames<MotionUnits> {
  static constexpr const char* kind = "motion units";
  static const std::vector<std::string>& names();  // pixels, uv
};

struct DepthFormat {
  CaptureDepth encoding = CaptureDepth::Normalized;
  double near_plane = 0.1, far_plane = 1000;
  double scale = 1;  // linear only
};

struct MotionComponent {
  std::vector<int> channels;  // one channel, or [high, low]
  double scale = 1, offset = 0;
};

struct MotionFormat {
  MotionComponent x{{0}}, y{{1}};
  MotionUnits units = MotionUnits::Pixels;
  bool declared = false;          // set when the YAML has the block (integer images need it)
};
config::Schema<MotionFormat> motion_format_schema();

// Decoders: `image` as read_image_file returns it. They throw cgsr::Error whose message says what
// is wrong; the caller adds the file and frame.
torch::Tensor decode_capture_color(const ImageFile& image, ColorAlpha alpha);  // uint8 [3,H,W]

struct CaptureDepthMap {
  torch::Tensor depth;  // float32 [1,H,W] linear, +inf = no geometry
  DepthPrecision precision;
};
CaptureDepthMap decode_capture_depth(const ImageFile& image, const DepthFormat& format);

torch::Tensor decode_capture_motion(const ImageFile& image, const MotionFormat& format);  // float32 [2,H,W] pixels

}  // namespace cgsr
