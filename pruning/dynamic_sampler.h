#pragma once
// The sampler of the dynamic pruning component (DPC, Fig. 4 of the paper): a few pooling and
// convolution layers over the rendering information of the current and the previous frame that
// score patterns. A hybrid-pruned model has one head scoring the pool's nested patterns
// (dynamic_pruning.h); the layers support U heads of K_u patterns each (grouped convolutions).
//
//   input  [N, 2C, g, g]: the chosen rendering channels of the current frame, average-pooled to
//          a g x g grid, and their change since the previous frame (sampler_input)
//   conv 3x3 (2C -> U*w), ReLU, 2x2 average pooling        one w-channel slice per head
//   conv 3x3 (U*w -> U*w, U groups), ReLU, global average  each head sees only its slice
//   conv 1x1 (U*w -> U*K, U groups)                       scores of the head's K patterns
// Scoring a frame costs three small kernels (well under 1 MMAC at g = 16), whatever the frame
// size.

#include <torch/nn/module.h>
#include <torch/nn/modules/conv.h>
#include <torch/types.h>

#include <string>
#include <vector>

#include "core/config.h"
#include "render_data/render_channels.h"

namespace cgsr {

struct SamplerOptions {
  std::vector<std::string> channels = {"depth", "normal_angle", "edge"};  // render_channels.h names
  int grid = 16;   // rendering information is average-pooled to grid x grid first
  int width = 8;   // hidden channels per unit
  std::vector<RenderChannel> render_channels() const { return parse_channels(channels); }
};
config::Schema<SamplerOptions> sampler_schema();

// The sampler input from the rendering information (`channels`, [N, C, H, W]) of the current and
// the previous frame (undefined: no previous frame, the change is zero). Motion is divided by
// the frame size so the input does not depend on the resolution, and clamped to one frame.
torch::Tensor sampler_input(const torch::Tensor& info, const torch::Tensor& previous,
                            const std::vector<RenderChannel>& channels, int grid);

class DynamicSamplersImpl : public torch::nn::Module {
 public:
  // `patterns[u]`: pool size of unit u (K_u >= 1).
  DynamicSamplersImpl(const SamplerOptions& options, std::vector<int> patterns);

  // Scores [N, U, K] with K = max K_u; a unit's entries beyond K_u are -1e9 (never chosen).
  torch::Tensor forward(const torch::Tensor& input);
  // The highest-scoring pattern of every unit, per item: [N][U].
  std::vector<std::vector<int>> choose(const torch::Tensor& input);

  // Keeps, per unit, the patterns `kept[u]` (old indices, in that order); static pruning drops
  // the patterns no frame selects. Choices among the kept patterns are unchanged.
  void keep_patterns(const std::vector<std::vector<int>>& kept);

  const std::vector<int>& patterns() const { return patterns_; }
  const SamplerOptions& options() const { return options_; }
  int64_t parameter_count() const;
  // Multiply-accumulates of one frame's scoring.
  int64_t macs() const;
  // [1, U, K] added to the head's scores: 0 for real patterns, -1e9 for padding (exporters
  // write it into the file).
  const torch::Tensor& invalid_mask() const { return invalid_; }

  torch::nn::Conv2d conv1{nullptr}, conv2{nullptr}, head{nullptr};

 private:
  void build_head();
  SamplerOptions options_;
  std::vector<int> patterns_;
  int64_t in_channels_;
  torch::Tensor invalid_;  // [1, U, K]: 0 for real patterns, -1e9 for padding
};
TORCH_MODULE(DynamicSamplers);

}  // namespace cgsr
