#include "models/importance/block_importance.h"

#include <torch/torch.h>

#include <algorithm>
#include <numeric>

#include "core/error.h"
#include "models/backbone_registry.h"

namespace cgsr {

std::vector<double> block_importance(const SRNetworkImpl& network) {
  const int blocks = network.spec().blocks;
  if (blocks <= 0) return {};
  const graph::Graph g = network.describe(/*training=*/false);
  std::vector<double> importance(blocks, 0.0);
  std::vector<bool> writes(blocks, false);
  for (int b = 0; b < blocks; ++b) {
    const std::string scope = "backbone.blocks." + std::to_string(b) + ".";
    const std::string own_groups = block_group(b, "");  // "block<b>_": the block's inner groups
    for (const auto& op : g.ops) {
      if (op.kind != graph::OpKind::Conv || !op.trainable || op.name.rfind(scope, 0) != 0) continue;
      const auto& layout = g.values[op.output].layout;
      const bool on_stream = std::none_of(layout.begin(), layout.end(), [&](const graph::Segment& s) {
        return s.group.rfind(own_groups, 0) == 0;
      });
      if (!on_stream) continue;
      importance[b] += op.weight.detach().abs().sum().item<double>();
      writes[b] = true;
    }
    CGSR_CHECK(writes[b], "block_importance: block " + std::to_string(b) + " of " + spec_summary(network.spec()) +
                              " has no op writing into the residual stream");
  }
  return importance;
}

std::vector<int> block_drop_order(const SRNetworkImpl& network) {
  const auto importance = block_importance(network);
  std::vector<int> order(importance.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return importance[a] != importance[b] ? importance[a] < importance[b] : a > b;
  });
  return order;
}

std::vector<int> kept_blocks(const std::vector<int>& drop_order, int blocks) {
  const int total = static_cast<int>(drop_order.size());
  CGSR_CHECK(blocks >= 0 && blocks <= total, "kept_blocks: " + std::to_string(blocks) + " of " +
                                                 std::to_string(total) + " blocks");
  std::vector<int> kept(drop_order.begin() + (total - blocks), drop_order.end());
  std::sort(kept.begin(), kept.end());
  return kept;
}

}  // namespace cgsr
