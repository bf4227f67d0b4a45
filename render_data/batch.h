#pragma once
// What training and evaluation consume: aligned LR/HR colour and rendering information.
// Rendering information is stacked in the order of render_channels.h, restricted to the
// channels requested by the consumer (a model's channel list).

#include <torch/types.h>

#include <array>
#include <memory>
#include <vector>

#include "render_data/render_channels.h"

namespace cgsr {

class BspBorderImage;  // bsp_border.h

struct Batch {
  torch::Tensor lr_color;  // [N, 3, h, w] float32 in [0,1]
  torch::Tensor lr_info;   // [N, C, h, w]; C = total_width(channels); may be empty when C = 0
  torch::Tensor hr_color;  // [N, 3, s*h, s*w]
  torch::Tensor hr_info;   // [N, C, s*h, s*w]
  std::vector<RenderChannel> channels;
  DepthEncoding depth_encoding = DepthEncoding::Log;  // of the depth channel in lr_info/hr_info
  std::vector<int> frames;  // frame index of each item in the sequence
  int scale = 2;
  // Whole frames of a data set with sub-pixel BSP border files: each item's LR BSP border image
  // (frame_batch fills it; empty for patches and for data sets without them).
  std::vector<std::shared_ptr<const BspBorderImage>> lr_bsp_border;
  // Whole frames: each item's LR jitter (Frame::jitter, LR pixels; frame_batch fills it; empty for
  // patches, whose augmentation would have to move it too).
  std::vector<std::array<double, 2>> lr_jitter;
};

}  // namespace cgsr
