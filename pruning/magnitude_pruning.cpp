#include "pruning/magnitude_pruning.h"

#include "core/error.h"

namespace cgsr {

Inheritance magnitude_prune(const SRNetworkImpl& net, double keep_rate) {
  if (!(keep_rate > 0 && keep_rate <= 1)) throw Error("magnitude pruning", "keep rate must be in (0, 1]");
  ArchSpec child = net.spec();
  child.geometry.enabled = false;
  for (const auto& unit : find_units(net.describe(false)))
    for (size_t i = 0; i < unit.groups.size(); ++i) {
      child.set_group_width(unit.groups[i], static_cast<int>(kept_count(unit.widths[i], keep_rate)));
    }
  Inheritance result = inherit(net, resolve_spec(child));
  result.network->eval();
  return result;
}

}  // namespace cgsr
