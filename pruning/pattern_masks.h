#pragma once
// Patterns of a pool (pattern_pool.h) applied to the dense network per sample, differentiably:
// how every pattern is trained (dynamic_pruning.h) before it runs as a smaller network.
//
// A sample's pattern weights [K] (a one-hot choice, or any mix) give each channel of each unit
// group a value in [0, 1]: the weighted sum of the patterns keeping it. Multiplying a layer's
// weights by it along their input channels, W (.) m, equals scaling those channels by m before
// the layer, so the masked network is run as the dense network with the values that feed
// convolutions scaled per sample and channel (the values models/importance/activation_importance.h
// reads). With a one-hot choice this is exactly the narrow network of that pattern: a removed channel
// contributes nothing to any convolution, and unit channels never reach a residual sum.
//
// The weights a pattern leaves out, W_P in Eq. 4 of the paper, are those attached to a removed
// channel (the rows writing it and the columns reading it), in proportion to 1 - m: their L1
// norm is the pruning penalty.

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

  // Per group, the sample masks [N, width] from pattern weights [N, K].
  std::map<std::string, torch::Tensor> group_masks(const torch::Tensor& pattern_weights) const;
  // The same for one pattern for every one of `n` samples.
  std::map<std::string, torch::Tensor> group_masks(int pattern, int64_t n) const;

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
  std::map<std::string, torch::Tensor> patterns_;  // group -> [K, width] of 0/1
  std::vector<bool> masked_;                          // per op: its output feeds a conv and carries unit channels
};

}  // namespace cgsr
