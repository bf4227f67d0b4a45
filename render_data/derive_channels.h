#pragma once
// Rendering information reconstructed from depth, for captures that lack it:
//   normals       view-space positions are back-projected from linear depth through a pinhole
//                 camera (vertical FOV, principal point at the image centre, square pixels);
//                 tangents are one-sided differences towards the neighbour with the smaller depth
//                 change (so they do not straddle a silhouette); n = normalize(tangent_y x
//                 tangent_x), turned to face the camera. Pixels without geometry get 0.
//   normal angle  angle between that normal and the direction to the camera / 90 degrees.
//   edges         edges.h on depth (at its stored precision) and normals when present (derived
//                 ones only from exact depth).

#include <torch/types.h>

#include <vector>

#include "render_data/edges.h"
#include "render_data/frame.h"

namespace cgsr {

// depth: [1,H,W] or [H,W] linear (+inf = no geometry). Returns float32 [3,H,W].
torch::Tensor normals_from_depth(const torch::Tensor& depth, double vfov_degrees);
// normal: [3,H,W] view space. Returns float32 [1,H,W] in [0,1], 0 where the normal is 0.
torch::Tensor normal_angle_from_normals(const torch::Tensor& normal, double vfov_degrees);

// Fills each channel of `derive` that `frame` lacks (edge, normal, normal_angle; depth must be
// present). Throws cgsr::Error for a channel that cannot be derived (depth, motion) or when the
// frame has no depth to derive from.
void derive_channels(Frame& frame, const std::vector<RenderChannel>& derive, double vfov_degrees,
                     const EdgeSettings& edges);

// Whether `channel` can be derived from depth.
bool derivable(RenderChannel channel);

}  // namespace cgsr
