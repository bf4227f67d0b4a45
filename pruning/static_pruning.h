#pragma once
// Static pruning: what the dynamic pruning components never select on a scene's frames is
// removed physically, giving a smaller network that runs with dense kernels anywhere (and
// exports like any other model).
//
// Removed: every channel of a pruning unit outside all selected patterns (the patterns no frame
// selects are dropped from the pool), the RIT rendering channels whose contribution
// |R_c| * ||RIT conv weights reading c||_1 is below `rit_threshold` times the largest one (at
// least one channel stays), and the training-only geometry head. On the frames the selection
// counts came from, the pruned network with its remaining patterns computes what the unpruned
// one did; dropping RIT channels changes the output by their (small) contribution.

#include <nlohmann/json.hpp>
#include <vector>

#include "core/config.h"
#include "models/inherit.h"
#include "models/sr_network.h"
#include "pruning/pattern_pool.h"

namespace cgsr {

struct StaticPruneOptions {
  double rit_threshold = 0.01;  // relative contribution below which a rendering channel is left out
};
config::Schema<StaticPruneOptions> static_prune_schema();

struct StaticPruning {
  SRNetwork network{nullptr};          // the smaller network
  PatternPool pool;                    // the selected patterns, in the smaller network's indices
  std::vector<std::vector<int>> kept;  // [unit] -> old indices of the patterns kept, in order
  std::map<std::string, std::vector<int64_t>> channels;  // group -> parent channels kept
  std::vector<std::string> rit_channels_dropped;
  nlohmann::ordered_json left_out;     // what was removed, for results.json
};

// `counts[u][k]`: frames on which unit u selected pattern k.
StaticPruning static_prune(const SRNetworkImpl& net, const PatternPool& pool,
                           const std::vector<std::vector<int64_t>>& counts, const StaticPruneOptions& options);

// Per RIT rendering channel (spec order): |R_c| * L1 of the RIT conv weights reading it.
std::vector<std::pair<std::string, double>> rit_channel_contributions(const SRNetworkImpl& net);

}  // namespace cgsr
