#pragma once
// Search strategies propose new subnets from the current population; the generation loop
// (search/search_loop.h) evaluates them and keeps the population. They see subnets and scores
// only. A registry builds them by name, each with its own options block:
//   evolution  NSGA-II: parents by binary tournament on Pareto rank and crowding, uniform
//              crossover, then per-gene mutation (the CGSR search, multi-objective)
//   random     subnets drawn uniformly from the space (the baseline at equal evaluations)
// Both start from the same first generation (search_loop.h): uniform samples of the space.

#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/registry.h"
#include "models/elastic.h"
#include "search/evaluator.h"

namespace cgsr {

struct Candidate {
  SubnetConfig subnet;
  std::string key;
  SubnetScore score;
  double quality = 0;    // what the search maximizes (search_loop.h); -inf for a failed candidate
  int generation = 0;
  bool failed = false;   // could not be scored (on_failure: worst)
};

// Options of the evolution strategy.
struct EvolutionOptions {
  double mutation_rate = 0.1;   // per gene
  double crossover_rate = 0.5;  // share of children made by crossover of two parents
};
config::Schema<EvolutionOptions> evolution_schema();

// The strategy and its own options block: `strategy: {type: evolution, mutation_rate: 0.2}`, or
// a bare name (`strategy: random`) for a strategy with its defaults.
struct StrategyOptions {
  std::string type = "evolution";
  EvolutionOptions evolution;  // read when type is evolution
};

class SearchStrategy {
 public:
  virtual ~SearchStrategy() = default;
  // Up to `count` subnets of the space, none of which `seen`, none twice; fewer when the space
  // offers no more. `population` is sorted best first (Pareto rank, then crowding; empty before
  // the first generation).
  virtual std::vector<SubnetConfig> propose(const std::vector<Candidate>& population, int count,
                                            const std::function<bool(const std::string&)>& seen,
                                            std::mt19937_64& rng) = 0;
};

// What a propose() usually does: calls `draw` until it has `count` subnets neither `seen` nor
// drawn twice, or until 50 x count attempts found no more (the space is exhausted).
std::vector<SubnetConfig> collect_unseen(int count, const std::function<bool(const std::string&)>& seen,
                                         const std::function<SubnetConfig()>& draw);

// A strategy by name: how its options block is read and written, and the factory.
struct StrategyType {
  std::function<void(const YAML::Node& block, StrategyOptions& options, const config::Cursor& at)> parse_options;
  std::function<void(const StrategyOptions& options, YAML::Node& block)> emit_options;
  std::function<std::unique_ptr<SearchStrategy>(const ElasticSpace& space, const StrategyOptions& options)> make;
};
// The process-wide table, evolution and random already in it. A built-in strategy is added in
// strategy.cpp; a program that embeds cgsr adds its own with strategy_registry().add(...) before
// it parses search configs (docs/extending.md).
Registry<StrategyType>& strategy_registry();
// parse_options of a strategy without options: only `type` may stand in its block.
void parse_no_strategy_options(const YAML::Node& block, StrategyOptions& options, const config::Cursor& at);

}  // namespace cgsr

namespace cgsr::config {
// `strategy:` as a bare name or a {type: Name, ...} block; written as the block.
template <>
struct Codec<StrategyOptions> {
  static StrategyOptions decode(const YAML::Node& n, const Cursor& at);
  static YAML::Node encode(const StrategyOptions& o);
};
}  // namespace cgsr::config
