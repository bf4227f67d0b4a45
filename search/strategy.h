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

// A strategy by name: how its options block is read and written, and the factory.
struct StrategyType {
  std::function<void(const YAML::Node& block, StrategyOptions& options, const config::Cursor& at)> parse_options;
  std::function<void(const StrategyOptions& options, YAML::Node& block)> emit_options;
  std::function<std::unique_ptr<SearchStrategy>(const ElasticSpace& space, const StrategyOptions& options)> make;
};
const Registry<StrategyType>& strategy_registry();

}  // namespace cgsr

namespace cgsr::config {
// `strategy:` as a bare name or a {type: Name, ...} block; written as the block.
template <>
struct Codec<StrategyOptions> {
  static StrategyOptions decode(const YAML::Node& n, const Cursor& at);
  static YAML::Node encode(const StrategyOptions& o);
};
}  // namespace cgsr::config
