#pragma once
// Per-sample regularizing patterns during fine-tuning (Eq. 3-4 of the paper).
//
// A unit's pattern for one sample is a weighted average of its pool's patterns (the weights come
// from the dynamic sampler: a softmax, or a one-hot choice): a value in [0, 1] per channel of
// each of its groups. Multiplying a layer's weights by the pattern along its input channels,
// W (.) m, equals scaling those input channels by m before the layer, so with per-sample patterns
// the masked network is run as the dense network with the values that feed convolutions scaled
// per sample and channel (the values activation_importance.h reads). With one-hot weights this
// is exactly the network executed with that pattern (pattern_executor.h): a removed channel then
// contributes nothing to any convolution, and pruning-unit channels never reach a residual sum.
//
// The weights the patterns mark less important, W_P in Eq. 4, are those attached to a channel
// (the rows writing it and the columns reading it) in proportion to 1 - m: their L1 norm is the
// pruning penalty.

#include <torch/types.h>

#include <map>
#include <string>
#include <vector>

#include "models/graph.h"
#include "models/sr_network.h"
#include "pruning/pattern_pool.h"

namespace cgsr {

class PatternMasks {
 public:
  // The graph holds `net`'s own parameters (gradients reach them); `net` must outlive this.
  PatternMasks(const SRNetworkImpl& net, const PatternPool& pool);

  // Per group, the sample patterns [N, width] from per-unit pattern weights [N, K_u].
  std::map<std::string, torch::Tensor> group_masks(const std::vector<torch::Tensor>& unit_weights) const;

  // The network output with the masks applied (differentiable in weights and masks).
  torch::Tensor forward(const torch::Tensor& lr_color, const torch::Tensor& info,
                        const std::map<std::string, torch::Tensor>& masks) const;

  // sum over groups and channels of mean_n(1 - m[n, c]) * ||weights attached to c||_1.
  torch::Tensor pruned_weight_l1(const std::map<std::string, torch::Tensor>& masks) const;

  // L1 norm of the weights attached to each channel of the unit groups (differentiable).
  std::map<std::string, torch::Tensor> attached_l1() const;

 private:
  graph::Graph graph_;
  const PatternPool& pool_;
  std::vector<std::vector<torch::Tensor>> patterns_;  // [unit][group]: [K_u, width] of 0/1
  std::vector<bool> masked_;                          // per op: its output feeds a conv and carries unit channels
};

}  // namespace cgsr
