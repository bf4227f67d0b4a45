#pragma once
// Static pruning: what the dynamic pruning component never selects on a scene's frames is
// removed physically, giving a smaller network that runs with dense kernels anywhere (and
// exports like any other model). Removed: the patterns no frame selects, every channel and block
// only they kept (the static network is the union of the selected patterns, pattern_pool.h), and
// the training-only geometry head. Each selected pattern computes exactly what it did before.

#include <nlohmann/json.hpp>
#include <vector>

#include "models/sr_network.h"
#include "pruning/pattern_pool.h"

namespace cgsr {

struct StaticPruning {
  SRNetwork network{nullptr};  // the smaller network
  PatternPool pool;            // the selected patterns, in the smaller network
  std::vector<int> kept;       // old indices of the patterns kept, in order
  nlohmann::ordered_json left_out;  // what was removed, for results.json
};

// `counts[k]`: frames on which pattern k was selected.
StaticPruning static_prune(const SRNetworkImpl& net, const PatternPool& pool, const std::vector<int64_t>& counts);

}  // namespace cgsr
