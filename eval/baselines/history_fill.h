#pragma once
// The history-fill upscaler: a classic temporal baseline that reads the `history` rendering channel
// (render_data/history_channel.h: the jittered LR samples of the frame and its predecessors,
// reprojected to the output grid). An output pixel that holds a sample takes its colour; every
// other pixel is the bicubic interpolation of the LR frame at the unjittered output grid
// (interpolation.h: upscale_bicubic_jittered; the engine knows its jitter). It is what
// accumulating samples in the output grid gives without any learning or blending, the floor a
// temporal network has to beat.

#include <torch/types.h>

#include <array>
#include <vector>

namespace cgsr {

// lr: [N,3,h,w] in [0,1]; history: [N,4,s*h,s*w] (r, g, b, recency; recency 0 where no sample);
// jitter: one per item (Batch::lr_jitter), or empty for unjittered frames. Returns [N,3,s*h,s*w]
// float32. Throws cgsr::Error when the shapes disagree.
torch::Tensor upscale_history_fill(const torch::Tensor& lr, const torch::Tensor& history, int scale,
                                   const std::vector<std::array<double, 2>>& jitter);

}  // namespace cgsr
