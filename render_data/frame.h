#pragma once
// One frame at one resolution in memory: the single representation every loader produces and
// the samplers consume. Kept compact so long sequences fit in memory: colour and edges as bytes,
// normals and normal angles as half floats; depth and motion stay float32 (depth spans 1e-3 to
// 1e6 metres and infinity; motion needs sub-pixel precision over hundreds of pixels).
// A channel that the data does not have (and was not derived) is an undefined tensor.

#include <torch/types.h>

#include <array>
#include <memory>
#include <vector>

#include "render_data/edges.h"
#include "render_data/gbuffer.h"
#include "render_data/render_channels.h"

namespace cgsr {

class BspBorderImage;  // bsp_border.h

struct Frame {
  int width = 0, height = 0;
  torch::Tensor color;         // uint8 [3,H,W], sRGB-encoded
  torch::Tensor depth;         // float32 [1,H,W], linear view depth; +inf where there is no geometry
  torch::Tensor normal;        // float16 [3,H,W], view-space unit normal; 0 where there is no geometry
  torch::Tensor normal_angle;  // float16 [1,H,W] in [0,1]
  torch::Tensor edge;          // uint8 [1,H,W], 0 or 1
  torch::Tensor motion;        // float32 [2,H,W], pixels (render_channels.h)
  // float32 [4,H,W]: the BSP border image resolved at this resolution (render_channels.h, derived
  // on load from the LR frame's colour and bsp_border; bsp_channel.h). float32: it is the BSP
  // upsampler's output number for number.
  torch::Tensor bsp;
  // float32 [4,H,W]: the reprojected LR samples of this frame and its predecessors (render_channels.h,
  // derived on load from the stored channels of the previous frames; history_channel.h).
  torch::Tensor history;
  // float32 [2,1,1]: the jitter channel (render_channels.h), the LR frame's jitter in LR pixels at
  // every resolution, derived on load; info() spreads it over the frame, crop() keeps it.
  torch::Tensor lr_jitter;
  // float32 [6,H,W]: the history_out channel's data part (render_channels.h): colour 0, the
  // reprojection's validity into the previous frame, the motion (history_channel.h).
  torch::Tensor history_out;
  DepthPrecision depth_precision;  // of `depth` as it was stored (exact unless read from integers)
  // The sub-pixel BSP border image, when the data set stores one at this resolution (cgsr data
  // sets rendered with bsp_border; bsp_border.h); null otherwise. crop() drops it: its lines are
  // in the whole frame's pixel coordinates.
  std::shared_ptr<const BspBorderImage> bsp_border;
  // Sub-pixel offset of this frame's projection, pixels of this resolution, each in [-0.5, 0.5):
  // the image content sits at p + jitter (render_data/jitter.h). {0, 0} when not jittered (every
  // resolution but the smallest of a jittered data set or capture, and a capture without a jitter
  // file). An integer crop keeps it.
  std::array<double, 2> jitter{0, 0};

  bool has(RenderChannel channel) const;
  std::vector<RenderChannel> channels() const;  // present channels, in the fixed order
  // float32 [3,H,W] in [0,1].
  torch::Tensor color_float() const;
  // float32 [total_width(channels),H,W] in the contract's form (depth through encode_depth).
  // Throws cgsr::Error when a requested channel is missing.
  torch::Tensor info(const std::vector<RenderChannel>& channels, DepthEncoding depth, double near_plane,
                     double far_plane) const;
  size_t bytes() const;  // memory held by the tensors
};

// A window of `f` (views of its tensors, no copy): columns x .. x + w - 1, rows y .. y + h - 1.
Frame crop(const Frame& f, int x, int y, int w, int h);

// Compacts a rendered G-buffer (colour quantized to 8 bits as it would be stored).
Frame frame_from_gbuffer(const GBuffer& g);

}  // namespace cgsr
