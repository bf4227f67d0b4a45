#include "models/importance/channel_importance.h"

namespace cgsr {

void add_position_scores(FrameImportance& importance, const graph::Layout& layout, const torch::Tensor& per_position) {
  int64_t offset = 0;
  for (const auto& s : layout) {
    const int64_t span = s.channels * s.repeat;
    if (s.prunable) {
      const auto channel = per_position.slice(0, offset, offset + span).view({s.channels, s.repeat}).sum(1);
      auto it = importance.find(s.group);
      if (it == importance.end())
        importance.emplace(s.group, channel);
      else
        it->second = it->second + channel;
    }
    offset += span;
  }
}

std::map<std::string, torch::Tensor> channel_importance(const graph::Graph& graph) {
  std::map<std::string, torch::Tensor> out;
  for (const auto& op : graph.ops)
    if (op.trainable && graph::op_traits(op.kind).has_tensors)
      add_position_scores(out, graph.values[op.output].layout, graph::output_channel_magnitude(op));
  return out;
}

std::map<std::string, torch::Tensor> channel_importance(const SRNetworkImpl& net) {
  return channel_importance(net.describe(false));
}

}  // namespace cgsr
