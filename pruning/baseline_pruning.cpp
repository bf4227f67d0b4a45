#include "pruning/baseline_pruning.h"

#include <torch/torch.h>

#include <algorithm>

#include "core/error.h"
#include "core/text.h"
#include "models/complexity.h"
#include "models/importance/importance_methods.h"
#include "pruning/pattern_pool.h"

namespace cgsr {

namespace {
ArchSpec pruned_spec(const SRNetworkImpl& net, double keep_rate) {
  ArchSpec child = net.spec();
  child.geometry.enabled = false;
  for (const auto& unit : find_units(net.describe(false)))
    for (size_t i = 0; i < unit.groups.size(); ++i)
      child.set_group_width(unit.groups[i], static_cast<int>(kept_count(unit.widths[i], keep_rate)));
  return resolve_spec(child);
}
}  // namespace

config::Schema<BaselineOptions> baseline_schema() {
  config::Schema<BaselineOptions> s;
  s.field("type", &BaselineOptions::type, "importance method that ranks the channels")
      .one_of(importance_methods().names());
  s.field("keep_rate", &BaselineOptions::keep_rate,
          "fraction of each unit group's channels kept; 0 = the rate matching the hybrid model's mean MACs")
      .check([](double v) { return v >= 0 && v <= 1; }, "must be in [0, 1]");
  return s;
}

std::string baseline_label(const BaselineOptions& options) {
  const std::string& paper_name = importance_methods().get(options.type).baseline_name;
  std::string label = paper_name.empty() ? options.type + " pruning" : paper_name;
  if (options.keep_rate > 0) label += " " + fixed(options.keep_rate, 2);
  return label;
}

Inheritance prune_to_rate(const SRNetworkImpl& net, const ChannelSelection& order, double keep_rate) {
  if (!(keep_rate > 0 && keep_rate <= 1)) throw Error("baseline pruning", "keep rate must be in (0, 1]");
  const ArchSpec child = pruned_spec(net, keep_rate);
  ChannelSelection kept;
  for (const auto& unit : find_units(net.describe(false)))
    for (const auto& g : unit.groups) {
      const auto it = order.find(g);
      CGSR_CHECK(it != order.end(), "baseline pruning: no channel order for layer group " + g);
      const auto n = static_cast<size_t>(child.group_width(g));
      CGSR_CHECK(n <= it->second.size(), "baseline pruning: the order of " + g + " is too short");
      std::vector<int64_t> top(it->second.begin(), it->second.begin() + static_cast<std::ptrdiff_t>(n));
      std::sort(top.begin(), top.end());
      kept[g] = std::move(top);
    }
  Inheritance result = inherit(net, child, kept);
  result.network->eval();
  return result;
}

Inheritance magnitude_prune(const SRNetworkImpl& net, double keep_rate) {
  const auto units = find_units(net.describe(false));
  return prune_to_rate(net, importance_order(units, {magnitude_importance(net, unit_groups(units))}), keep_rate);
}

double keep_rate_for_macs(const SRNetworkImpl& net, int64_t macs, int64_t lr_width, int64_t lr_height) {
  const auto cost = [&](double rate) {
    return complexity(*SRNetwork(pruned_spec(net, rate)), lr_width, lr_height).macs;
  };
  double low = 1e-6, high = 1.0;
  if (cost(high) <= macs) return high;
  if (cost(low) > macs) return low;
  for (int i = 0; i < 30; ++i) {
    const double mid = 0.5 * (low + high);
    (cost(mid) <= macs ? low : high) = mid;
  }
  return low;
}

}  // namespace cgsr
