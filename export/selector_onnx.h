#pragma once
// The dynamic pruning component of a hybrid-pruned model (pruning/dynamic_sampler.h) as a small
// ONNX model, opset 13, at one fixed LR size: what a game engine runs before each frame to pick
// the pattern file to run.
//
//   inputs   render_info, previous_render_info   [1, C, H, W] float: the sampler's rendering
//            channels (render_channels.h order and widths, motion in pixels) of this frame and
//            the previous one; on a first frame (no previous one) pass render_info twice
//   outputs  scores   [1, K] float: one score per pattern (higher is chosen)
//            pattern  [1] int64: argmax of scores, the pattern to run
//
// Inside, exactly sampler_input() then DynamicSamplersImpl::forward():
//   motion channels x (1/W, 1/H), clipped to [-1, 1]         (Slice, Mul, Clip, Concat)
//   adaptive average pooling to grid x grid                  (AveragePool when H and W divide by the grid,
//                                                              else MatMul by fixed pooling matrices)
//   concat(current, current - previous), conv3x3, ReLU
//   2x2 average pooling with ceil_mode (a partial window at an odd edge is divided by the cells it
//     covers, as torch does; written as MatMuls for an odd grid, AveragePool for an even one)
//   grouped conv3x3, ReLU, GlobalAveragePool, 1x1 head, + the invalid-pattern mask, ArgMax

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <torch/types.h>

#include "pruning/dynamic_sampler.h"

namespace cgsr {

inline constexpr const char* kSelectorInfoInput = "render_info";
inline constexpr const char* kSelectorPreviousInput = "previous_render_info";
inline constexpr const char* kSelectorScores = "scores";
inline constexpr const char* kSelectorPattern = "pattern";

// Averaging matrix [out, in] of 1-D box pooling: row i averages input cells [begin(i), end(i)).
// Adaptive pooling (torch::adaptive_avg_pool2d): begin floor(i*in/out), end ceil((i+1)*in/out).
torch::Tensor adaptive_pool_matrix(int64_t in, int64_t out);
// avg_pool (kernel k, stride k, no padding, ceil_mode): begin i*k, end min(i*k + k, in); a
// partial last window is divided by the cells it covers.
torch::Tensor ceil_pool_matrix(int64_t in, int64_t k);

// Serialized, checked ONNX model of `samplers` (one unit: the hybrid's single head) at LR size
// width x height. Throws cgsr::Error for a sampler with several units or a size below the grid.
std::string selector_onnx_bytes(const DynamicSamplersImpl& samplers, int64_t width, int64_t height,
                                const std::vector<std::pair<std::string, std::string>>& metadata = {});

}  // namespace cgsr
