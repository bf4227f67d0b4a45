#pragma once
// Temporal stability from rendered motion vectors: how much an output changes between
// consecutive frames beyond what the scene's motion explains (flicker, crawling edges).

#include <torch/types.h>

namespace cgsr {

// Backward-warps `previous` [N,C,H,W] into the current frame: the pixel at p takes the value of
// `previous` at p + motion (render_channels.h convention; motion [N,2,H,W] in pixels of this
// resolution), bilinearly. `valid` [N,1,H,W] marks pixels whose source lies inside the frame.
struct Warped {
  torch::Tensor image;
  torch::Tensor valid;
};
Warped warp_previous(const torch::Tensor& previous, const torch::Tensor& motion);

// Mean absolute difference between `current` and the warped `previous` over valid pixels; the
// same figure for the ground truth is the floor a perfect upscaler would reach (shading and
// disocclusions change between frames too).
double warping_error(const torch::Tensor& current, const torch::Tensor& previous, const torch::Tensor& motion);

}  // namespace cgsr
