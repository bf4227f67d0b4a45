#pragma once
// The sub-pixel BSP border image resolved at a resolution `scale` times its own: what the BSP
// border upsampler outputs (eval/baselines/bsp_border_upsampler.h) and the `bsp` rendering channel
// (render_channels.h) holds. One implementation serves both, so a network's `bsp` input is the
// upsampler's image number for number.
//
// An output pixel whose centre falls in a border pixel takes the colour of the leaf its centre
// falls in, so the edge stays where the geometry put it; every other output pixel is the bicubic
// interpolation of the LR colour (Keys a = -0.75, the pixel-centre convention of docs/design.md,
// as upscale_bicubic), except that a tap on a border pixel reads that pixel's leaf on the output
// centre's side of its lines (they extend beyond the pixel): no colour bleeds across an edge into
// the neighbours. The leaves hold 8-bit sRGB like the colour image.

#include <torch/types.h>

#include "render_data/bsp_border.h"

namespace cgsr {

struct ResolvedBspBorder {
  torch::Tensor color;     // float32 [3, s*h, s*w], sRGB-encoded in [0,1] (bicubic may overshoot slightly)
  torch::Tensor coverage;  // float32 [1, s*h, s*w]: 1 where the pixel's centre lies in a border pixel
};

// lr_color: [3,h,w] in [0,1] (any float type), of the image's size; scale >= 1. Throws cgsr::Error
// (naming `what`, e.g. the frame) when the sizes disagree.
ResolvedBspBorder resolve_bsp_border(const torch::Tensor& lr_color, const BspBorderImage& image, int scale,
                                     const std::string& what = "BSP border image");

// The `bsp` channel's tensor [4, s*h, s*w]: colour then coverage.
torch::Tensor bsp_channel(const torch::Tensor& lr_color, const BspBorderImage& image, int scale,
                          const std::string& what = "BSP border image");

}  // namespace cgsr
