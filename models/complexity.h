#pragma once
// Parameters and multiply-accumulates (MACs) of a network for a given LR input size, per layer
// and in total, counted on the inference graph (graph.h), so the geometry head never counts.
//
// Convention (docs/design.md): a conv costs (weights) x (output pixels) = out * in/groups * k * k * H * W
// MACs; biases, activations, element-wise ops (additions, attention products, the RIT gate),
// resizes, pooling and pixel shuffles cost nothing. Fixed 1x1 colour convs (EDSR's mean shift,
// SRCNN's Y mode) count MACs but no parameters, as in the published counts. Parameters are the
// trainable tensors of the inference network.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "models/graph.h"

namespace cgsr {

class SRNetworkImpl;

struct LayerCost {
  std::string name;  // op name (module path)
  std::string kind;  // "conv", "channel_affine"
  int64_t in_channels = 0, out_channels = 0, kernel = 0, groups = 1;
  int64_t out_width = 0, out_height = 0;
  int64_t params = 0;
  int64_t macs = 0;
  bool trainable = true;
};

struct Complexity {
  int64_t lr_width = 0, lr_height = 0;  // input
  int64_t hr_width = 0, hr_height = 0;  // output
  std::vector<LayerCost> layers;        // ops with weights, in graph order
  int64_t params = 0;
  int64_t macs = 0;
};

Complexity complexity(const graph::Graph& graph, int64_t lr_width, int64_t lr_height);
Complexity complexity(const SRNetworkImpl& net, int64_t lr_width, int64_t lr_height);

// The LR input size whose output fits `hr_width` x `hr_height` (floor division by the scale):
// 1280x720 at x3 -> 426x240, as in the reference MAC counts.
std::pair<int64_t, int64_t> lr_size_for_output(int64_t hr_width, int64_t hr_height, int scale);

// "70.52G", "316.3G", "57.3M" with 4 significant digits.
std::string format_count(double count);

nlohmann::ordered_json to_json(const Complexity& c);

}  // namespace cgsr
