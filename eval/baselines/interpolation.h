#pragma once
// Classic interpolating upscalers. All use the pixel-centre convention of docs/design.md: output
// pixel j samples the input at (j + 0.5) / scale - 0.5, with edge pixels replicated.

#include <torch/types.h>

#include <array>
#include <vector>

namespace cgsr {

torch::Tensor upscale_nearest(const torch::Tensor& lr, int scale);
torch::Tensor upscale_bilinear(const torch::Tensor& lr, int scale);
torch::Tensor upscale_bicubic(const torch::Tensor& lr, int scale);  // Keys cubic, a = -0.75
// Bicubic of a jittered LR frame (render_data/jitter.h: its content sits at p + jitter) at the
// unjittered output grid: output pixel j samples the input at (j + 0.5) / scale - 0.5 + jitter.
// jitter: one (x, y) offset per item, in LR pixels. At jitter 0 it is upscale_bicubic.
torch::Tensor upscale_bicubic_jittered(const torch::Tensor& lr, int scale, const std::vector<std::array<double, 2>>& jitter);
// Lanczos (lobes >= 1): 2 * lobes taps per output along each axis, applied as two banded passes
// (rows, then columns) in the input's precision (float for half/bfloat16), CPU only. The result
// is the dense product resampling_matrix(rows) @ lr @ resampling_matrix(cols)^T up to float
// rounding. A NaN or Inf texel reaches only the outputs whose taps cover it.
torch::Tensor upscale_lanczos(const torch::Tensor& lr, int scale, int lobes = 3);

// The resampling matrix [out, in] of a separable kernel along one axis, normalized per row.
// `kernel(x)` gives the weight of a tap at distance x; taps beyond `support` are ignored.
// A reference for tests; upscale_lanczos applies the same weights without the matrix.
torch::Tensor resampling_matrix(int64_t in_size, int64_t out_size, double support,
                                const std::function<double(double)>& kernel);

}  // namespace cgsr
