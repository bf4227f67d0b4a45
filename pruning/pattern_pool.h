#pragma once
// The pattern pool: per pruning unit, the channel patterns most often important on the training
// frames, found by frequency-based sorting.
//
// For every frame, each group of a unit ranks its channels by their importance under that frame
// (activation_importance.h) and keeps the top kept_count(width, keep_rate): the frame's pattern.
// Exact repeats of a pattern are rare when a group has tens of channels, so near-identical
// patterns are merged. The rule, applied per unit until `size` patterns are found or every frame
// is covered:
//   1. d(p, q) = number of channels kept by p and not by q (patterns keep the same count per
//      group, so d is symmetric); two patterns are near-identical when
//      d <= floor(merge_tolerance * channels a pattern keeps). merge_tolerance 0 = exact matches.
//   2. Among the frames not yet covered, take the frame pattern with the most near-identical
//      frame patterns (ties: more exact repeats, then the earlier frame).
//   3. The pool entry is the consensus of that cluster: per group, the channels selected most
//      often by its frames (ties: higher summed importance, then lower index). Its frequency is
//      the cluster's size. Mark the cluster's frames covered.
// Finally every frame is assigned the pool entry nearest to its own pattern (ties: the more
// frequent entry); the assignment is what the dynamic samplers first learn to predict.

#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include <torch/types.h>

#include "core/config.h"
#include "pruning/channel_selection.h"
#include "pruning/prunable_units.h"

namespace cgsr {

struct PoolOptions {
  double keep_rate = 0.5;         // fraction of each group's channels a pattern keeps
  int size = 8;                   // patterns per unit (K)
  double merge_tolerance = 0.25;  // see the rule above
};
config::Schema<PoolOptions> pool_schema();

struct Pattern {
  ChannelSelection keep;  // every group of the unit, kept channel indices
  int frames = 0;         // frames whose pattern this entry stands for
};

struct UnitPatterns {
  PrunableUnit unit;
  std::vector<Pattern> patterns;  // most frequent first
};

struct PatternPool {
  std::vector<UnitPatterns> units;

  // The channels a choice (one pattern index per unit) keeps, for every unit group.
  ChannelSelection selection(const std::vector<int>& choice) const;
  // Per unit group, the union of every pattern's channels.
  ChannelSelection union_selection() const;
  int max_patterns() const;
};

// Per frame: layer group -> channel importance [width] (CPU float).
using FrameImportance = std::map<std::string, torch::Tensor>;

struct PoolBuild {
  PatternPool pool;
  std::vector<std::vector<int>> assignment;  // [frame][unit] -> pattern index
};

PoolBuild build_pattern_pool(const std::vector<PrunableUnit>& units, const std::vector<FrameImportance>& frames,
                             const PoolOptions& options);

// The top kept_count(width, keep_rate) channels of each group of `unit` (sorted indices).
ChannelSelection top_channels(const PrunableUnit& unit, const FrameImportance& importance, double keep_rate);

nlohmann::ordered_json to_json(const PatternPool& pool);
// `units` are those of the network the pool belongs to (find_units of its graph); the JSON must
// match them. Errors name `context`.
PatternPool pool_from_json(const nlohmann::ordered_json& j, const std::vector<PrunableUnit>& units,
                           const std::string& context);

}  // namespace cgsr
