#include "pruning/equal_latency_controls.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "core/error.h"
#include "models/elastic.h"
#include "models/latency_table.h"
#include "pruning/prunable_units.h"

namespace cgsr {

const std::vector<std::string>& EnumNames<ControlKind>::names() {
  static const std::vector<std::string> names = {"magnitude", "uniform"};
  return names;
}

std::string control_label(ControlKind kind) { return kind == ControlKind::Magnitude ? "MMP" : "uniform width"; }

SubnetConfig control_subnet(const SRNetworkImpl& net, ControlKind kind, double rate) {
  if (!(rate > 0 && rate <= 1)) throw Error("control", "keep rate must be in (0, 1]");
  const graph::Graph g = net.describe(false);
  std::set<std::string> groups;
  if (kind == ControlKind::Magnitude) {
    for (const auto& unit : find_units(g))
      groups.insert(unit.groups.begin(), unit.groups.end());
  }
  SubnetConfig sub = full_subnet(net.spec());
  for (auto& [group, width] : sub.widths)
    if (kind == ControlKind::Uniform || groups.count(group))
      width = std::max<int64_t>(1, std::llround(rate * static_cast<double>(width)));
  return sub;
}

GraphCost measured_latency(int64_t lr_width, int64_t lr_height, int runs) {
  return [=](const graph::Graph& g) { return measure_graph_latency(g, lr_width, lr_height, runs); };
}

ControlNetwork control_at_rate(const SRNetworkImpl& net, ControlKind kind, double rate, const GraphCost& cost) {
  // Sorting by magnitude makes the leading channels the largest (make_elastic's order).
  const SRNetwork sorted = make_elastic(net, ElasticOptions{}).network;
  ControlNetwork c;
  c.rate = rate;
  c.network = materialize_subnet(*sorted, control_subnet(*sorted, kind, rate), /*geometry_head=*/false);
  c.network->eval();
  c.latency_ms = cost(c.network->describe(false));
  return c;
}

ControlNetwork control_at_latency(const SRNetworkImpl& net, ControlKind kind, double latency_ms, const GraphCost& cost,
                                  int steps) {
  double low = 0.05, high = 1.0;
  ControlNetwork best = control_at_rate(net, kind, high, cost);
  if (best.latency_ms <= latency_ms) return best;
  best = control_at_rate(net, kind, low, cost);
  if (best.latency_ms > latency_ms) return best;
  for (int i = 0; i < steps; ++i) {
    const double mid = 0.5 * (low + high);
    ControlNetwork c = control_at_rate(net, kind, mid, cost);
    if (c.latency_ms <= latency_ms) {
      low = mid;
      best = std::move(c);
    } else {
      high = mid;
    }
  }
  return best;
}

}  // namespace cgsr
