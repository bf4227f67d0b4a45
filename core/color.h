#pragma once
// Colour conversions on float tensors with channels at dim -3 (CHW or NCHW).

#include <torch/types.h>

namespace cgsr {

// IEC 61966-2-1 transfer functions; values outside [0,1] are clamped first.
torch::Tensor srgb_to_linear(const torch::Tensor& srgb);
torch::Tensor linear_to_srgb(const torch::Tensor& linear);

// Luma Y of ITU-R BT.601 in studio range, as in the SR literature (MATLAB's rgb2ycbcr):
// Y = 16/255 + (65.481 R + 128.553 G + 24.966 B) / 255, for RGB in [0,1]. Keeps the channel dim.
torch::Tensor rgb_to_y(const torch::Tensor& rgb);

}  // namespace cgsr
