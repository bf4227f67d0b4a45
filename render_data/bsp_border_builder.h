#pragma once
// One pixel's sub-pixel BSP (bsp_border.h) from samples inside it: which surface each sample
// sees and its colour, and candidate split lines (the renderer's projected triangle edges).
// Greedy, top down: a region (the samples on one side of the lines above it) is split by the
// candidate that leaves the fewest samples outside their side's majority surface, then the one
// of lowest Gini impurity, with samples on both sides; ties go to the lower priority (the
// renderer: the nearer triangle's edge, the occluder's silhouette), then to the earlier
// candidate. A region stops being split when it sees one surface, when no candidate lowers its
// Gini impurity, or at the maximum depth. Leaves get the mean colour of their own samples (those
// inside the pixel), of all their samples when they have none. Deterministic: the result depends on the inputs' order only.

#include <array>
#include <optional>
#include <vector>

#include "render_data/bsp_border.h"

namespace cgsr {

// The render config's `bsp_border` block.
struct BspBorderSettings {
  int depth = 0;    // lines on a root-to-leaf path, 0..kMaxBspDepth; 0 = no BSP border files
  int samples = 4;  // samples per pixel side: samples^2 per pixel label surfaces and colour leaves
  bool enabled() const { return depth > 0; }
};

struct BspSample {
  double x = 0, y = 0;  // image pixel coordinates
  bool own = true;      // inside the pixel; others (just outside) colour only leaves without own samples
  int32_t surface = 0;  // samples with equal values see the same surface
  std::array<float, 3> color{};  // sRGB in [0,1]
};

struct BspCandidate {
  BspLine line;
  double priority = 0;  // lower wins ties
};

// Throws cgsr::Error naming the setting when `settings` cannot build trees for a width x height
// image: depth outside 1..kMaxBspDepth, samples outside 2..16, or a supersampled view larger
// than cgsr renders (core/image_header.h).
void check_bsp_border_settings(const BspBorderSettings& settings, int width, int height);

// Empty when the samples see one surface or no candidate separates them.
std::optional<BspTree> build_pixel_bsp(const std::vector<BspSample>& samples, const std::vector<BspCandidate>& candidates,
                                       int max_depth);

// The line through (x0, y0) and (x1, y1), normalized (a^2 + b^2 = 1); nullopt for coincident points.
std::optional<BspLine> line_through(double x0, double y0, double x1, double y1);

}  // namespace cgsr
