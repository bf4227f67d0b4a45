#include "models/importance/channel_importance.h"

namespace cgsr {

std::map<std::string, torch::Tensor> channel_importance(const graph::Graph& graph) {
  std::map<std::string, torch::Tensor> out;
  for (const auto& op : graph.ops) {
    if (!op.trainable || !graph::op_traits(op.kind).has_tensors) continue;
    const torch::Tensor per_position = graph::output_channel_magnitude(op);
    int64_t offset = 0;
    for (const auto& s : graph.values[op.output].layout) {
      const int64_t span = s.channels * s.repeat;
      if (s.prunable) {
        const auto channel = per_position.slice(0, offset, offset + span).view({s.channels, s.repeat}).sum(1);
        auto it = out.find(s.group);
        if (it == out.end())
          out.emplace(s.group, channel);
        else
          it->second = it->second + channel;
      }
      offset += span;
    }
  }
  return out;
}

std::map<std::string, torch::Tensor> channel_importance(const SRNetworkImpl& net) {
  return channel_importance(net.describe(false));
}

}  // namespace cgsr
