#include "pruning/pattern_networks.h"

#include <torch/torch.h>

#include "core/error.h"

namespace cgsr {

PatternNetworks::PatternNetworks(const SRNetworkImpl& net, PatternPool pool, Precision precision,
                                 const PatternCalibration& calibration)
    : pool_(std::move(pool)), precision_(precision) {
  CGSR_CHECK(pool_.spec == net.spec(), "pattern networks: the pool belongs to another network");
  torch::NoGradGuard no_grad;
  for (const auto& pattern : pool_.patterns) {
    graph::Graph g = subnet_graph(net, pattern);
    for (auto& op : g.ops) {  // a snapshot: later training of the network must not change a pattern
      if (op.weight.defined()) op.weight = op.weight.detach().clone();
      if (op.bias.defined()) op.bias = op.bias.detach().clone();
      if (op.scale.defined()) op.scale = op.scale.detach().clone();
      if (op.shift.defined()) op.shift = op.shift.detach().clone();
    }
    FusedGraph::Options o;
    o.precision = precision;
    if (precision == Precision::Int8) o.calibration = calibrate(g, calibration.frames, calibration.method);
    options_.push_back(std::move(o));
    graphs_.push_back(std::move(g));
  }
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
    for (int p = 0; p < size(); ++p) fused_[p] = std::make_unique<FusedGraph>(graphs_[p], options_[p]);
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
