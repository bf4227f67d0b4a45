#include "models/importance/activation_importance.h"

#include <torch/torch.h>

#include <optional>
#include <set>

#include "core/error.h"

namespace cgsr {

std::vector<size_t> conv_input_producers(const graph::Graph& graph, const std::vector<std::string>& groups) {
  const std::set<std::string> dynamic(groups.begin(), groups.end());
  std::set<int> conv_inputs;
  for (const auto& op : graph.ops)
    if (graph::op_traits(op.kind).mixes_channels) conv_inputs.insert(op.inputs[0]);
  std::vector<size_t> out;
  for (size_t i = 0; i < graph.ops.size(); ++i) {
    const int v = graph.ops[i].output;
    if (!conv_inputs.count(v)) continue;
    for (const auto& s : graph.values[v].layout)
      if (s.prunable && dynamic.count(s.group)) {
        out.push_back(i);
        break;
      }
  }
  return out;
}

FrameImportance frame_importance(SRNetworkImpl& net, const Batch& batch, const std::vector<std::string>& groups,
                                 ActivationScore score) {
  const graph::Graph g = net.describe(false);
  const auto producers = conv_input_producers(g, groups);
  const std::set<std::string> dynamic(groups.begin(), groups.end());

  std::vector<std::pair<size_t, torch::Tensor>> captured;  // (op index, value)
  std::vector<bool> wanted(g.ops.size(), false);
  for (size_t i : producers) wanted[i] = true;
  const bool taylor = score == ActivationScore::Taylor;
  const graph::OpObserver observe = [&](size_t index, const torch::Tensor& y) {
    if (wanted[index]) {
      if (taylor) y.retain_grad();
      captured.emplace_back(index, y);
    }
    return y;
  };

  const auto inputs = network_inputs(g, batch.lr_color, net.info_input(batch));
  const bool was_training = net.is_training();
  net.eval();
  FrameImportance sums;
  {
    std::optional<torch::NoGradGuard> no_grad;
    if (!taylor) no_grad.emplace();
    const auto out = graph::run(g, inputs, nullptr, observe);
    if (taylor) {
      const auto image = out.front().second;
      torch::mse_loss(image, batch.hr_color).backward();  // the reconstruction loss L (L2)
    }
    torch::NoGradGuard no_grad_after;
    for (const auto& [index, value] : captured) {
      torch::Tensor per_position;  // [C_value]
      if (taylor) {
        CGSR_CHECK(value.grad().defined(), "importance: no gradient reached " + g.ops[index].name);
        per_position = (value * value.grad()).sum({0, 2, 3});
      } else {
        per_position = value.abs().mean({0, 2, 3});
      }
      int64_t offset = 0;
      for (const auto& s : g.values[g.ops[index].output].layout) {
        const int64_t span = s.channels * s.repeat;
        if (s.prunable && dynamic.count(s.group)) {
          const auto channel = per_position.slice(0, offset, offset + span).view({s.channels, s.repeat}).sum(1);
          auto it = sums.find(s.group);
          if (it == sums.end())
            sums.emplace(s.group, channel.clone());
          else
            it->second += channel;
        }
        offset += span;
      }
    }
  }
  for (auto& p : net.parameters()) p.mutable_grad() = torch::Tensor();
  if (was_training) net.train();
  FrameImportance out;
  for (const auto& group : groups) {
    const auto it = sums.find(group);
    CGSR_CHECK(it != sums.end(), "importance: group " + group + " never reaches a convolution");
    out[group] = (taylor ? it->second.abs() : it->second).to(torch::kFloat).contiguous();
  }
  return out;
}

}  // namespace cgsr
