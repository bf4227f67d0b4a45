#pragma once
// The BSP border upsampler: a classic baseline that reads the renderer's sub-pixel BSP border
// images (render_data/bsp_border.h) and resolves them at the output size with
// render_data/bsp_channel.h (the `bsp` rendering channel's code). An output pixel whose centre falls in a border pixel of the
// input takes the colour of the leaf its centre falls in, so the edge stays where the geometry
// put it; every other output pixel is the bicubic interpolation of the input (interpolation.h,
// the same pixel-centre convention), except that a tap on a border pixel reads that pixel's leaf
// on the output centre's side of its lines (they extend beyond the pixel): no colour bleeds
// across an edge into the neighbours. The leaves hold 8-bit sRGB like the colour image.

#include <torch/types.h>

#include <vector>

#include "render_data/bsp_border.h"

namespace cgsr {

// lr: [N,3,h,w] in [0,1]; bsp: one image per item, of size w x h. Returns [N,3,s*h,s*w] float32.
// Throws cgsr::Error when the images are missing or of another size.
torch::Tensor upscale_bsp_border(const torch::Tensor& lr, const std::vector<const BspBorderImage*>& bsp, int scale);

}  // namespace cgsr
