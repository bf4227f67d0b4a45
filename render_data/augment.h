#pragma once
// The 8 flips and 90-degree rotations of an image (the dihedral group), applied consistently to
// colour and rendering information. Vectors are transformed, not only moved:
//   image coordinates x right, y down; motion and jitter (dx, dy) are in these coordinates;
//   normals are view space (x right, y up, z towards the camera).
// A horizontal flip negates motion x, jitter x and normal x; a vertical flip negates their y; a
// 90-degree counter-clockwise rotation (as displayed) maps motion and jitter (dx, dy) -> (dy, -dx)
// and normal (x, y) -> (-y, x). Depth, normal angle, edges and colour only move.
// Colour augmentation (ColorAugmentation below) changes colour values, never geometry.

#include <torch/types.h>

#include <vector>

#include "render_data/render_channels.h"

namespace cgsr {

struct Augmentation {
  bool flip = false;  // horizontal flip first
  int rotations = 0;  // then this many 90-degree counter-clockwise rotations (0..3)
  static Augmentation from_index(int index);  // 0..7
};

// A colour change applied alike to an item's LR and HR colour (not to its rendering information):
// the colour channels reordered and scaled by one gain, clamped to [0, 1]. Rendered colour is
// albedo times light per channel, so a permuted or brighter scene is another plausible one: a
// network trained on one level's palette and brightness then sees others.
struct ColorAugmentation {
  int permutation = 0;  // 0..5: one of the 6 orders of R, G, B (0 keeps it)
  float gain = 1.0f;
  static constexpr float kMaxGain = 1.6f;  // gains are drawn log-uniformly in [1/kMaxGain, kMaxGain]
  // From two uniform draws in [0, 1).
  static ColorAugmentation from_uniform(double u_permutation, double u_gain);
};

// `image`: [C,H,W] or [N,C,H,W] with channels that move only (colour, depth, edges, ...).
torch::Tensor augment_image(const torch::Tensor& image, const Augmentation& a);
// `info`: [C,H,W] or [N,C,H,W] stacked in the order of `channels` (render_channels.h).
torch::Tensor augment_info(const torch::Tensor& info, const std::vector<RenderChannel>& channels, const Augmentation& a);

// `color`: [3,H,W] or [N,3,H,W] in [0, 1].
torch::Tensor augment_color(const torch::Tensor& color, const ColorAugmentation& a);
// The colour augmentation of the rendering information: the colour of the bsp and history channels
// (images of the scene's colours) gets the one its frame's colour gets; other channels are not
// colours (history's recency stays).
torch::Tensor augment_info_color(const torch::Tensor& info, const std::vector<RenderChannel>& channels,
                                 const ColorAugmentation& a);

}  // namespace cgsr
