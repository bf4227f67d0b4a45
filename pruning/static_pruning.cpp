#include "pruning/static_pruning.h"

#include "core/error.h"

namespace cgsr {

StaticPruning static_prune(const SRNetworkImpl& net, const PatternPool& pool, const std::vector<int64_t>& counts) {
  StaticPruning result;
  const PatternPool chosen = chosen_patterns(pool, counts, result.kept);
  const SubnetConfig all = pool_union(chosen);
  result.network = materialize_subnet(net, all, /*geometry_head=*/false);
  result.network->eval();
  result.pool = rebase_pool(chosen, all, result.network->spec());
  result.left_out = nlohmann::ordered_json::object();
  auto patterns = nlohmann::ordered_json::array();
  for (int k = 0; k < pool.size(); ++k)
    if (counts[k] == 0) patterns.push_back(k);
  result.left_out["patterns"] = patterns;
  result.left_out["blocks"] = static_cast<int>(net.spec().blocks) - static_cast<int>(all.blocks.size());
  result.left_out["channels"] = nlohmann::ordered_json::object();
  for (const auto& [group, width] : full_subnet(net.spec()).widths) {
    const int64_t kept = subnet_width(all, group, width);
    if (kept < width) result.left_out["channels"][group] = {{"width", width}, {"kept", kept}};
  }
  return result;
}

}  // namespace cgsr
