#pragma once
// Search strategies propose new specs from the survivors of the previous generation. They see
// specs and fitness values only (search/evaluator.h); a registry builds them by name:
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

struct StrategyOptions {
  double initial_spread = 0.5;  // mutation rate that draws the first generation around the parent
  double mutation_rate = 0.15;  // per gene
  double crossover_rate = 0.5;  // share of children made by crossover of two survivors
};
config::Schema<StrategyOptions> strategy_schema();

class SearchStrategy {
 public:
  virtual ~SearchStrategy() = default;
  // Up to `count` specs in the space, none of which `seen`, none twice; fewer when the space
  // offers no more. `survivors` are sorted best first (empty before the first generation).
  virtual std::vector<ArchSpec> propose(const std::vector<Candidate>& survivors, int count,
                                        const std::function<bool(const std::string&)>& seen,
                                        std::mt19937_64& rng) = 0;
};

using StrategyFactory =
    std::function<std::unique_ptr<SearchStrategy>(const SearchSpace& space, const StrategyOptions& options)>;
const Registry<StrategyFactory>& strategy_registry();

}  // namespace cgsr
