#pragma once
// The pattern pool of a hybrid-pruned model: K subnets (models/subnet.h) of one network, widest
// (slowest) first, that the dynamic pruning component chooses among per frame. They are points
// of the search's Pareto front of an elastic network (pool_from_front), so every pattern is a
// trained subnet and the pool spans latencies around the search's pick; they need not be nested,
// and any of them may skip blocks. Each runs as views of the one network's weights.
//
//   PatternPool pool = pool_from_front(front, pick.score.latency_ms, options);   // elastic names
//   SubnetConfig all = pool_union(pool);                  // what the static network keeps
//   SRNetwork net = materialize_subnet(*elastic, all, false);
//   PatternPool in_net = rebase_pool(pool, all, net->spec());                   // net's names

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/config.h"
#include "models/arch_spec.h"
#include "models/subnet.h"
#include "search/strategy.h"

namespace cgsr {

struct PoolOptions {
  // Pattern k is the front point whose predicted latency is nearest latency_factors[k] times the
  // pick's (each point once; fewer patterns when the front has fewer points).
  std::vector<double> latency_factors = {1.5, 1.25, 1.0, 0.8, 0.65};
};
config::Schema<PoolOptions> pool_schema();

struct PatternPool {
  ArchSpec spec;                      // the network the patterns are subnets of
  std::vector<SubnetConfig> patterns;  // widest first

  int size() const { return static_cast<int>(patterns.size()); }
  // The share of the network's channels pattern k keeps (skipped blocks keep none).
  double channel_fraction(int k) const;
};

// The pool from a Pareto front (candidates fastest first) of subnets of `spec`, around the pick.
PatternPool pool_from_front(const ArchSpec& spec, const std::vector<Candidate>& front, double pick_latency_ms,
                            const PoolOptions& options);

// The subnet holding every pattern: each group's widest width, every block some pattern keeps.
SubnetConfig pool_union(const PatternPool& pool);

// The pool as subnets of the network `materialize_subnet(net, onto)` builds, whose spec is
// `spec`: blocks renumbered in the order `onto` keeps them, their groups renamed with them.
PatternPool rebase_pool(const PatternPool& pool, const SubnetConfig& onto, const ArchSpec& spec);

// The patterns some frame chose (`counts[k]` > 0), in order; an Error when none was chosen.
PatternPool chosen_patterns(const PatternPool& pool, const std::vector<int64_t>& counts, std::vector<int>& kept);

nlohmann::ordered_json to_json(const PatternPool& pool);
// `spec` is the network the pool belongs to; every pattern must be a subnet of it. Errors name
// `context`.
PatternPool pool_from_json(const nlohmann::ordered_json& j, const ArchSpec& spec, const std::string& context);

}  // namespace cgsr
