#include "pruning/pattern_masks.h"

#include <torch/torch.h>

#include "core/error.h"
#include "pruning/activation_importance.h"

namespace cgsr {

PatternMasks::PatternMasks(const SRNetworkImpl& net, const PatternPool& pool)
    : graph_(net.describe(false)), pool_(pool) {
  std::vector<PrunableUnit> units;
  for (const auto& u : pool_.units) units.push_back(u.unit);
  masked_.assign(graph_.ops.size(), false);
  for (size_t i : conv_input_producers(graph_, units)) masked_[i] = true;
  for (const auto& u : pool_.units) {
    std::vector<torch::Tensor> per_group;
    for (size_t g = 0; g < u.unit.groups.size(); ++g) {
      auto p = torch::zeros({static_cast<int64_t>(u.patterns.size()), u.unit.widths[g]});
      for (size_t k = 0; k < u.patterns.size(); ++k)
        for (int64_t c : u.patterns[k].keep.at(u.unit.groups[g])) p[k][c] = 1.0f;
      per_group.push_back(p);
    }
    patterns_.push_back(per_group);
  }
}

std::map<std::string, torch::Tensor> PatternMasks::group_masks(const std::vector<torch::Tensor>& unit_weights) const {
  CGSR_CHECK(unit_weights.size() == pool_.units.size(), "pattern masks: one weight tensor per unit");
  std::map<std::string, torch::Tensor> out;
  for (size_t u = 0; u < pool_.units.size(); ++u) {
    const auto& w = unit_weights[u];
    CGSR_CHECK(w.dim() == 2 && w.size(1) == static_cast<int64_t>(pool_.units[u].patterns.size()),
               "pattern masks: weights of unit " + pool_.units[u].unit.name + " must be [N, K]");
    for (size_t g = 0; g < pool_.units[u].unit.groups.size(); ++g)
      out[pool_.units[u].unit.groups[g]] = w.matmul(patterns_[u][g]);
  }
  return out;
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
    for (size_t g = 0; g < u.unit.groups.size(); ++g) out[u.unit.groups[g]] = torch::zeros({u.unit.widths[g]});
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
    for (size_t index : u.unit.ops) {
      const auto& op = graph_.ops[index];
      if (op.kind == graph::OpKind::Conv) {
        auto rows = op.weight.abs().sum({1, 2, 3});
        if (op.bias.defined()) rows = rows + op.bias.abs();
        accumulate(rows, graph_.values[op.output].layout);
        accumulate(op.weight.abs().sum({0, 2, 3}), graph_.values[op.inputs[0]].layout);
      } else if (op.kind == graph::OpKind::ChannelAffine) {
        torch::Tensor t = op.scale.defined() ? op.scale.abs() : torch::zeros({op.shift.numel()});
        if (op.shift.defined()) t = t + op.shift.abs();
        accumulate(t, graph_.values[op.output].layout);
      }
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
