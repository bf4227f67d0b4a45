#include "pruning/pattern_networks.h"

#include <torch/torch.h>

#include "core/error.h"

namespace cgsr {

PatternNetworks::PatternNetworks(const SRNetworkImpl& net, PatternPool pool) : pool_(std::move(pool)) {
  torch::NoGradGuard no_grad;
  graph::Graph widest = net.describe(false);
  for (auto& op : widest.ops) {  // a snapshot: the views must not track later training
    if (op.weight.defined()) op.weight = op.weight.detach().clone();
    if (op.bias.defined()) op.bias = op.bias.detach().clone();
    if (op.scale.defined()) op.scale = op.scale.detach().clone();
    if (op.shift.defined()) op.shift = op.shift.detach().clone();
  }
  const auto units = find_units(widest);
  CGSR_CHECK(units.size() == pool_.units.size(), "pattern networks: the pool does not match the network's units");
  for (size_t u = 0; u < units.size(); ++u)
    CGSR_CHECK(units[u].groups == pool_.units[u].groups && units[u].widths == pool_.units[u].widths,
               "pattern networks: pool unit " + pool_.units[u].name + " does not match the network");
  for (int k = 0; k < pool_.size(); ++k) graphs_.push_back(select_channels(widest, pool_.selection(k)));
  fused_.resize(graphs_.size());
}

PatternNetworks::~PatternNetworks() = default;

const graph::Graph& PatternNetworks::graph(int k) const {
  CGSR_CHECK(k >= 0 && k < size(), "pattern index " + std::to_string(k) + " out of range");
  return graphs_[k];
}

torch::Tensor PatternNetworks::run(int k, const torch::Tensor& lr_color, const torch::Tensor& info) {
  graph(k);  // checks k
  // Every pattern is built at the first run: an engine loads all patterns before its first frame,
  // so switching to a pattern never pays for building it (and is never timed doing so).
  if (!fused_[k])
    for (int p = 0; p < size(); ++p) fused_[p] = std::make_unique<FusedGraph>(graphs_[p]);
  return fused_[k]->run(lr_color, info);
}

Complexity PatternNetworks::cost(int k, int64_t lr_width, int64_t lr_height) const {
  return complexity(graph(k), lr_width, lr_height);
}

std::vector<LatencyStats> PatternNetworks::measure_latency(const torch::Tensor& lr_color, const torch::Tensor& info,
                                                           int rounds) {
  std::vector<std::function<void()>> runs;
  for (int k = 0; k < size(); ++k) runs.push_back([&, k] { run(k, lr_color, info); });
  return measure_latency_interleaved(runs, /*warmup=*/2, rounds);
}

}  // namespace cgsr
