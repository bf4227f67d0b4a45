#pragma once
// Bicubic upsampling by an integer factor f as a convolution, for runtimes without a cubic
// Resize (OpenCV DNN 4.6).
//
// With half-pixel centres, output pixel f*k + p samples input k + d_p, d_p = (p + 0.5) / f - 0.5,
// which lies in (-0.5, 0.5) for every phase p. Its four cubic taps (a = -0.75, PyTorch's and
// ONNX's default) sit at offsets floor(d_p) - 1 .. floor(d_p) + 2, all inside [-2, 2]. So on the
// input padded by 2 with edge replication (PyTorch clamps sample indices at the border), a 5x5
// kernel per phase (py, px), the outer product of the 1-D phase kernels, gives every output
// pixel; the f*f phase maps then interleave by depth-to-space (CRD order).

#include <torch/types.h>

#include <cstdint>

namespace cgsr {

inline constexpr double kBicubicA = -0.75;
inline constexpr int64_t kBicubicPhaseRadius = 2;  // edge padding on each side; kernel size 5

// The 1-D cubic kernel of phase p, 5 taps for offsets -2..2, in double.
torch::Tensor bicubic_phase_taps(int64_t factor, int64_t phase);

// [f*f, 1, 5, 5] float32: output channel py*f + px holds the 2-D kernel of phase (py, px).
torch::Tensor bicubic_phase_kernels(int64_t factor);

}  // namespace cgsr
