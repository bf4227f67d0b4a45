#pragma once
// Static pruning: what the dynamic pruning component never selects on a scene's frames is
// removed physically, giving a smaller network that runs with dense kernels anywhere (and
// exports like any other model).
//
// Removed: the patterns no frame selects, and with them the channels only wider patterns keep
// (the static network is the widest selected pattern; the pool is nested, so it holds every
// other selected pattern), the RIT rendering channels whose contribution
// |R_c| * ||RIT conv weights reading c||_1 is below `rit_threshold` times the largest one (at
// least one channel stays), and the training-only geometry head. Each selected pattern computes
// what it did before, up to the (small) contribution of the dropped RIT channels.

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
  PatternPool pool;                    // the selected patterns, in the smaller network
  std::vector<int> kept;               // old indices of the patterns kept, in order
  std::map<std::string, std::vector<int64_t>> channels;  // group -> parent channels kept
  std::vector<std::string> rit_channels_dropped;
  nlohmann::ordered_json left_out;     // what was removed, for results.json
};

// `counts[k]`: frames on which pattern k was selected.
StaticPruning static_prune(const SRNetworkImpl& net, const PatternPool& pool, const std::vector<int64_t>& counts,
                           const StaticPruneOptions& options);

// Per RIT rendering channel (spec order): |R_c| * L1 of the RIT conv weights reading it.
std::vector<std::pair<std::string, double>> rit_channel_contributions(const SRNetworkImpl& net);

}  // namespace cgsr
