#pragma once
// The 8 flips and 90-degree rotations of an image (the dihedral group), applied consistently to
// colour and rendering information. Vectors are transformed, not only moved:
//   image coordinates x right, y down; motion (dx, dy) is in these coordinates;
//   normals are view space (x right, y up, z towards the camera).
// A horizontal flip negates motion x and normal x; a vertical flip negates motion y and normal
// y; a 90-degree counter-clockwise rotation (as displayed) maps motion (dx, dy) -> (dy, -dx) and
// normal (x, y) -> (-y, x). Depth, normal angle, edges and colour only move.

#include <torch/types.h>

#include <vector>

#include "render_data/render_channels.h"

namespace cgsr {

struct Augmentation {
  bool flip = false;  // horizontal flip first
  int rotations = 0;  // then this many 90-degree counter-clockwise rotations (0..3)
  static Augmentation from_index(int index);  // 0..7
};

// `image`: [C,H,W] or [N,C,H,W] with channels that move only (colour, depth, edges, ...).
torch::Tensor augment_image(const torch::Tensor& image, const Augmentation& a);
// `info`: [C,H,W] or [N,C,H,W] stacked in the order of `channels` (render_channels.h).
torch::Tensor augment_info(const torch::Tensor& info, const std::vector<RenderChannel>& channels, const Augmentation& a);

}  // namespace cgsr
