#pragma once
// The pattern pool of a hybrid-pruned network: K nested patterns that differ in cost, from the
// widest (k = 0) to the narrowest (k = K - 1). Pattern k keeps, of every layer group of every
// pruning unit (prunable_units.h), the first widths[k][group] channels.
//
// "The first channels" means something because the network's channels are reordered by
// importance once (order_channels): channel 0 of a group matters most on the training frames.
// A pattern's weights are then leading slices of the widest weights (views, no gather), a
// narrower pattern keeps a subset of every wider one's channels, and the widest pattern is the
// network itself: the static network that hybrid pruning ships is a pattern that was trained.
//
//   Inheritance ordered = order_channels(*net, units, importance);   // same outputs, sorted channels
//   PatternPool pool = nested_pool(find_units(ordered.network->describe(false)), {1.0, 0.7, 0.5});
//   graph::Graph narrow = select_channels(ordered.network->describe(false), pool.selection(2));

#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include <torch/types.h>

#include "core/config.h"
#include "models/importance/channel_importance.h"
#include "models/inherit.h"
#include "models/sr_network.h"
#include "models/channel_selection.h"
#include "pruning/prunable_units.h"

namespace cgsr {

struct PoolOptions {
  // Pattern k keeps kept_count(width, keep_rates[k]) channels of every unit group. Strictly
  // decreasing; the first is usually 1 (the static network keeps every channel it was given).
  std::vector<double> keep_rates = {1.0, 0.75, 0.5, 0.35};
};
config::Schema<PoolOptions> pool_schema();

struct PatternPool {
  std::vector<PrunableUnit> units;                      // of the network the pool belongs to
  std::vector<std::map<std::string, int64_t>> widths;   // [pattern][group] -> channels kept (a prefix)

  int size() const { return static_cast<int>(widths.size()); }
  // The channels pattern k keeps: {group: 0, 1, ..., widths[k][group] - 1}.
  ChannelSelection selection(int k) const;
  // The fraction of the unit channels pattern k keeps (summed over groups).
  double channel_fraction(int k) const;
};

// The pool of nested patterns over `units` (widest first); rates must be strictly decreasing in
// (0, 1], and no two patterns may keep the same channels.
PatternPool nested_pool(const std::vector<PrunableUnit>& units, const std::vector<double>& keep_rates);

// The pool restricted to `kept` patterns (indices, increasing), in the network that keeps the
// widest of them: what static pruning leaves when some patterns are never chosen.
PatternPool keep_patterns(const PatternPool& pool, const std::vector<int>& kept,
                          const std::vector<PrunableUnit>& narrowed_units);

// Per group of `units`: channel indices by decreasing importance, each frame's importance
// normalized to sum 1 first so that every frame counts alike (ties: the lower index first).
ChannelSelection importance_order(const std::vector<PrunableUnit>& units, const std::vector<FrameImportance>& frames);

// The same network with every unit group's channels permuted into `order` (a permutation per
// group): it computes the same outputs (up to float summation order).
Inheritance order_channels(const SRNetworkImpl& net, const ChannelSelection& order);

nlohmann::ordered_json to_json(const PatternPool& pool);
// `units` are those of the network the pool belongs to (find_units of its graph); the JSON must
// match them. Errors name `context`.
PatternPool pool_from_json(const nlohmann::ordered_json& j, const std::vector<PrunableUnit>& units,
                           const std::string& context);

}  // namespace cgsr
