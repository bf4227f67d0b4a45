#include "pruning/equal_latency_controls.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "core/error.h"
#include "models/elastic.h"
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

ControlNetwork control_at_rate(const SRNetworkImpl& net, ControlKind kind, double rate, const NetworkCost& cost) {
  // Sorting by magnitude makes the leading channels the largest (make_elastic's order).
  const SRNetwork sorted = make_elastic(net, ElasticOptions{}).network;
  ControlNetwork c;
  c.rate = rate;
  c.network = materialize_subnet(*sorted, control_subnet(*sorted, kind, rate), /*geometry_head=*/false);
  c.network->eval();
  c.cost = cost(c.network);
  return c;
}

ControlNetwork control_at_latency(const SRNetworkImpl& net, ControlKind kind, double target, const NetworkCost& cost,
                                  int steps) {
  double low = 0.05, high = 1.0;
  ControlNetwork best = control_at_rate(net, kind, high, cost);
  if (best.cost <= target) return best;
  best = control_at_rate(net, kind, low, cost);
  if (best.cost > target) return best;
  for (int i = 0; i < steps; ++i) {
    const double mid = 0.5 * (low + high);
    ControlNetwork c = control_at_rate(net, kind, mid, cost);
    if (c.cost <= target) {
      low = mid;
      best = std::move(c);
    } else {
      high = mid;
    }
  }
  return best;
}

}  // namespace cgsr
