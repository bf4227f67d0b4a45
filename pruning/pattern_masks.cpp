#include "pruning/pattern_masks.h"

#include <torch/torch.h>

#include "core/error.h"
#include "models/importance/activation_importance.h"

namespace cgsr {

PatternMasks::PatternMasks(const SRNetworkImpl& net, const PatternPool& pool)
    : graph_(net.describe(false)), pool_(pool) {
  masked_.assign(graph_.ops.size(), false);
  for (size_t i : conv_input_producers(graph_, unit_groups(pool_.units))) masked_[i] = true;
  for (const auto& u : pool_.units)
    for (size_t g = 0; g < u.groups.size(); ++g) {
      auto p = torch::zeros({pool_.size(), u.widths[g]});
      for (int k = 0; k < pool_.size(); ++k) p[k].slice(0, 0, pool_.widths[k].at(u.groups[g])).fill_(1.0f);
      patterns_[u.groups[g]] = p;
    }
}

std::map<std::string, torch::Tensor> PatternMasks::group_masks(const torch::Tensor& pattern_weights) const {
  CGSR_CHECK(pattern_weights.dim() == 2 && pattern_weights.size(1) == pool_.size(),
             "pattern masks: pattern weights must be [N, K]");
  std::map<std::string, torch::Tensor> out;
  for (const auto& [group, p] : patterns_) out[group] = pattern_weights.matmul(p);
  return out;
}

std::map<std::string, torch::Tensor> PatternMasks::group_masks(int pattern, int64_t n) const {
  CGSR_CHECK(pattern >= 0 && pattern < pool_.size(), "pattern masks: pattern index out of range");
  return group_masks(torch::one_hot(torch::full({n}, pattern, torch::kLong), pool_.size()).to(torch::kFloat));
}

torch::Tensor PatternMasks::forward(const torch::Tensor& lr_color, const torch::Tensor& info,
                                    const std::map<std::string, torch::Tensor>& masks) const {
  const int64_t n = lr_color.size(0);
  const graph::OpObserver observe = [&](size_t index, const torch::Tensor& y) {
    if (!masked_[index]) return y;
    std::vector<torch::Tensor> parts;
    for (const auto& s : graph_.values[graph_.ops[index].output].layout) {
      const auto it = s.prunable ? masks.find(s.group) : masks.end();
      if (it == masks.end()) {
        parts.push_back(torch::ones({n, s.channels * s.repeat}, y.options()));
      } else {
        CGSR_CHECK(it->second.size(0) == n, "pattern masks: batch size of the masks");
        parts.push_back(s.repeat > 1 ? it->second.repeat_interleave(s.repeat, 1) : it->second);
      }
    }
    const auto mask = torch::cat(parts, 1);
    return y * mask.view({n, mask.size(1), 1, 1});
  };
  for (const auto& [name, value] : graph::run(graph_, network_inputs(graph_, lr_color, info), nullptr, observe))
    if (name == "image") return value;
  throw Error("pattern masks", "the graph has no image output", ErrorKind::Internal);
}

std::map<std::string, torch::Tensor> PatternMasks::attached_l1() const {
  std::map<std::string, torch::Tensor> out;
  for (const auto& u : pool_.units)
    for (size_t g = 0; g < u.groups.size(); ++g) out[u.groups[g]] = torch::zeros({u.widths[g]});
  // Adds a per-position norm along an axis to the channels of the unit groups in its layout.
  const auto accumulate = [&](const torch::Tensor& per_position, const graph::Layout& layout) {
    int64_t offset = 0;
    for (const auto& s : layout) {
      const int64_t span = s.channels * s.repeat;
      const auto it = s.prunable ? out.find(s.group) : out.end();
      if (it != out.end())
        it->second = it->second + per_position.slice(0, offset, offset + span).view({s.channels, s.repeat}).sum(1);
      offset += span;
    }
  };
  for (const auto& u : pool_.units)
    for (size_t index : u.ops) {
      const auto& op = graph_.ops[index];
      const auto traits = graph::op_traits(op.kind);
      if (!traits.has_tensors) continue;
      accumulate(graph::output_channel_magnitude(op), graph_.values[op.output].layout);
      if (traits.mixes_channels) accumulate(op.weight.abs().sum({0, 2, 3}), graph_.values[op.inputs[0]].layout);
    }
  return out;
}

torch::Tensor PatternMasks::pruned_weight_l1(const std::map<std::string, torch::Tensor>& masks) const {
  auto total = torch::zeros({});
  for (const auto& [group, l1] : attached_l1()) {
    const auto it = masks.find(group);
    CGSR_CHECK(it != masks.end(), "pattern masks: no mask for group " + group);
    total = total + ((1.0 - it->second).mean(0) * l1).sum();
  }
  return total;
}

}  // namespace cgsr
