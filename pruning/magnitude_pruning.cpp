#include "pruning/magnitude_pruning.h"

#include "core/error.h"
#include "models/complexity.h"

namespace cgsr {

namespace {
ArchSpec pruned_spec(const SRNetworkImpl& net, double keep_rate) {
  ArchSpec child = net.spec();
  child.geometry.enabled = false;
  for (const auto& unit : find_units(net.describe(false)))
    for (size_t i = 0; i < unit.groups.size(); ++i) {
      child.set_group_width(unit.groups[i], static_cast<int>(kept_count(unit.widths[i], keep_rate)));
    }
  return resolve_spec(child);
}
}  // namespace

Inheritance magnitude_prune(const SRNetworkImpl& net, double keep_rate) {
  if (!(keep_rate > 0 && keep_rate <= 1)) throw Error("magnitude pruning", "keep rate must be in (0, 1]");
  Inheritance result = inherit(net, pruned_spec(net, keep_rate));
  result.network->eval();
  return result;
}

double magnitude_rate_for_macs(const SRNetworkImpl& net, int64_t macs, int64_t lr_width, int64_t lr_height) {
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
