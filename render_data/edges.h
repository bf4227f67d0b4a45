#pragma once
// Object edges from a G-buffer: used by the renderer (depth + normals + ids) and by loaders
// that derive a missing edge channel from depth alone; and the widened edge region on which
// evaluation measures quality.
//
// A pair of 4-neighbour pixels (p, q) is a discontinuity when any of these holds:
//   depth   1/z is affine in pixel coordinates on any plane, so each side's linear extrapolation
//           of 1/z predicts the other side on smooth geometry. The pair is a depth edge when both
//           predictions (from p's side and from q's side) miss by more than
//           depth_threshold x max(1/z_p, 1/z_q). Geometry next to empty pixels (sky) is an edge.
//   ids     the object ids differ (when ids are given and id_changes is on).
//   crease  the angle between the normals exceeds crease_angle degrees (when normals are given).
// Depth read from an integer image is only known to a storage step: a smooth slope becomes a
// staircase. With a DepthPrecision the depth test widens its tolerance by the steps of the pixels
// involved, so staircases are not edges and jumps larger than the quantisation still are.
// The nearer pixel of a discontinuous pair is marked (ties: the left/top one), so edges are one
// pixel wide and sit on the foreground object's silhouette.

#include <torch/types.h>

namespace cgsr {

struct EdgeSettings {
  float depth_threshold = 0.08f;  // relative 1/z extrapolation error
  float crease_angle = 40.0f;     // degrees
  bool id_changes = true;
};

// One storage step of a depth map in 1/z at inverse depth w: inverse_step + linear_step * w^2
// (a step in 1/z for z-buffer encodings, a step in z, dz/z^2 in 1/z, for linear ones). Zero:
// exact (float) depth.
struct DepthPrecision {
  double inverse_step = 0;  // 1/metres
  double linear_step = 0;   // metres
  bool exact() const { return inverse_step == 0 && linear_step == 0; }
  double step_at(double inverse_depth) const { return inverse_step + linear_step * inverse_depth * inverse_depth; }
};

// depth: float32 [H,W] or [1,H,W] linear depth (+inf or 0 where there is no geometry);
// normal: float32 [3,H,W] or undefined; ids: int32 [H,W]/[1,H,W] or undefined.
// Returns float32 [1,H,W] with values 0 and 1.
torch::Tensor detect_edges(const torch::Tensor& depth, const torch::Tensor& normal, const torch::Tensor& ids,
                           const EdgeSettings& settings, const DepthPrecision& precision = {});

// The edge map grown by one pixel in every direction (3x3 maximum, the window clamped at the
// borders): the one-pixel-wide silhouettes plus the pixels an upscaler blends across them.
// edges: [H,W] or [1,H,W], any type, nonzero = edge. Returns bool of the same shape.
torch::Tensor dilate_edges(const torch::Tensor& edges);

}  // namespace cgsr
