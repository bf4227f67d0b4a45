#pragma once
// Sub-pixel jitter of the low-resolution frames (the FSR 2 / DLSS convention): frame f's
// projection is offset by a point of the Halton(2, 3) sequence, phase f mod `phases`, shifted to
// [-0.5, 0.5) pixels of that resolution, so consecutive frames sample different points of each
// pixel and a temporal upscaler can gather them. The offset moves the image content: a point
// projected to pixel coordinates p without jitter lands on p + offset. Motion vectors exclude
// the jitter (render_channels.h).

#include <string>

#include "core/config.h"
#include "render_data/vec_math.h"

namespace cgsr {

struct JitterSettings {
  std::string sequence = "none";  // none | halton
  int phases = 8;                 // offsets before the sequence repeats
  bool enabled() const { return sequence != "none"; }
};

config::Schema<JitterSettings> jitter_settings_schema();

// The radical inverse of `index` (>= 1) in `base` (>= 2): 1/2, 1/4, 3/4, 1/8, ... for base 2.
double halton(int index, int base);

// The offset of frame `frame` (>= 0) in pixels, each component in [-0.5, 0.5): Halton points
// 1 .. phases, point (frame mod phases) + 1 (point 0 of the sequence is (0, 0) and would repeat
// the pixel centre of an unjittered render). {0, 0} when jitter is off.
Vec2 jitter_offset(const JitterSettings& settings, int frame);

}  // namespace cgsr
