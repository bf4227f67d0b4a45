#include "pruning/pattern_executor.h"

#include <torch/torch.h>

#include <set>

#include "core/error.h"

namespace cgsr {

PatternExecutor::PatternExecutor(const SRNetworkImpl& net, PatternPool pool) : pool_(std::move(pool)) {
  torch::NoGradGuard no_grad;
  const graph::Graph g = net.describe(false);
  const auto units = find_units(g);
  CGSR_CHECK(units.size() == pool_.units.size(), "pattern executor: the pool does not match the network's units");
  working_ = g;
  // The working graph must not alias the network's parameters (it swaps tensors in and out).
  for (auto& op : working_.ops) {
    if (op.weight.defined()) op.weight = op.weight.detach();
    if (op.bias.defined()) op.bias = op.bias.detach();
    if (op.scale.defined()) op.scale = op.scale.detach();
    if (op.shift.defined()) op.shift = op.shift.detach();
  }
  prepared_.resize(units.size());
  for (size_t u = 0; u < units.size(); ++u) {
    CGSR_CHECK(units[u].groups == pool_.units[u].unit.groups && units[u].widths == pool_.units[u].unit.widths,
               "pattern executor: pool unit " + pool_.units[u].unit.name + " does not match the network");
    const std::set<std::string> groups(units[u].groups.begin(), units[u].groups.end());
    std::vector<int> values;
    for (size_t v = 0; v < g.values.size(); ++v)
      for (const auto& s : g.values[v].layout)
        if (s.prunable && groups.count(s.group)) {
          values.push_back(static_cast<int>(v));
          break;
        }
    for (const auto& pattern : pool_.units[u].patterns) {
      check_selection(g, pattern.keep, "pattern of unit " + units[u].name);
      Prepared p;
      for (size_t index : units[u].ops) {
        const auto t = select_op_tensors(g, g.ops[index], pattern.keep);
        const auto own = [](const torch::Tensor& x) { return x.defined() ? x.detach().contiguous() : x; };
        p.ops.push_back({index, own(t.weight), own(t.bias), own(t.scale), own(t.shift)});
      }
      for (int v : values) p.layouts.emplace_back(v, selected_layout(g.values[v].layout, pattern.keep));
      prepared_[u].push_back(std::move(p));
    }
  }
  current_.assign(units.size(), -1);
}

void PatternExecutor::apply(const std::vector<int>& choice) {
  if (choice.size() != prepared_.size())
    throw Error("pattern executor", "a choice needs one pattern per unit (" + std::to_string(prepared_.size()) +
                                        "), got " + std::to_string(choice.size()));
  for (size_t u = 0; u < choice.size(); ++u) {
    if (choice[u] < 0 || choice[u] >= static_cast<int>(prepared_[u].size()))
      throw Error("pattern executor", "unit " + pool_.units[u].unit.name + " has " +
                                          std::to_string(prepared_[u].size()) + " patterns, chosen " +
                                          std::to_string(choice[u]));
    if (current_[u] == choice[u]) continue;
    const Prepared& p = prepared_[u][choice[u]];
    for (const auto& t : p.ops) {
      auto& op = working_.ops[t.op];
      op.weight = t.weight;
      op.bias = t.bias;
      op.scale = t.scale;
      op.shift = t.shift;
    }
    for (const auto& [v, layout] : p.layouts) working_.values[v].layout = layout;
    current_[u] = choice[u];
  }
}

torch::Tensor PatternExecutor::run(const torch::Tensor& lr_color, const torch::Tensor& info,
                                   const std::vector<int>& choice) {
  torch::NoGradGuard no_grad;
  apply(choice);
  for (const auto& [name, value] : graph::run(working_, network_inputs(working_, lr_color, info)))
    if (name == "image") return value;
  throw Error("pattern executor", "the graph has no image output", ErrorKind::Internal);
}

const graph::Graph& PatternExecutor::graph_for(const std::vector<int>& choice) {
  apply(choice);
  return working_;
}

Complexity PatternExecutor::cost(const std::vector<int>& choice, int64_t lr_width, int64_t lr_height) {
  return complexity(graph_for(choice), lr_width, lr_height);
}

}  // namespace cgsr
