#pragma once
// Search strategies propose new specs from the survivors of the previous generation: selection,
// mutation and crossover live here, the generation loop (search/search_loop.h) keeps the
// generations, history and pick. They see specs and fitness values only (search/evaluator.h);
// a registry builds them by name, each with its own options block:
//   evolution  mutation and crossover of the survivors' genes (the CGSR search)
//   random     specs drawn uniformly from the space (the baseline at equal budget)

#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/registry.h"
#include "search/evaluator.h"
#include "search/search_space.h"

namespace cgsr {

struct Candidate {
  ArchSpec spec;
  std::string key;
  CandidateScore score;
  double fitness = 0;
  int generation = 0;
};

// Options of the evolution strategy (the CGSR search).
struct EvolutionOptions {
  double initial_spread = 0.5;  // mutation rate that draws the first generation around the parent
  double mutation_rate = 0.15;  // per gene
  double crossover_rate = 0.5;  // share of children made by crossover of two survivors
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
  // Up to `count` specs in the space, none of which `seen`, none twice; fewer when the space
  // offers no more. `survivors` are sorted best first (empty before the first generation).
  virtual std::vector<ArchSpec> propose(const std::vector<Candidate>& survivors, int count,
                                        const std::function<bool(const std::string&)>& seen,
                                        std::mt19937_64& rng) = 0;
};

// A strategy by name: how its options block is read and written, and the factory.
struct StrategyType {
  std::function<void(const YAML::Node& block, StrategyOptions& options, const config::Cursor& at)> parse_options;
  std::function<void(const StrategyOptions& options, YAML::Node& block)> emit_options;
  std::function<std::unique_ptr<SearchStrategy>(const SearchSpace& space, const StrategyOptions& options)> make;
};
const Registry<StrategyType>& strategy_registry();

}  // namespace cgsr

namespace cgsr::config {
// `strategy:` as a bare name or a {type: Name, ...its options} block; written as the block.
template <>
struct Codec<StrategyOptions> {
  static StrategyOptions decode(const YAML::Node& n, const Cursor& at);
  static YAML::Node encode(const StrategyOptions& o);
};
}  // namespace cgsr::config
