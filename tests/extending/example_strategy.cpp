// The search strategy of docs/extending.md: hill climbing. Each generation proposes neighbours
// of the best subnet so far: copies of it with a few genes mutated. Its config:
//
//   strategy: hill_climb
#include "search/genetic_operators.h"
#include "search/strategy.h"

namespace cgsr {

class HillClimb : public SearchStrategy {
 public:
  explicit HillClimb(const ElasticSpace& space) : space_(space) {}

  std::vector<SubnetConfig> propose(const std::vector<Candidate>& population, int count,
                                    const std::function<bool(const std::string&)>& seen,
                                    std::mt19937_64& rng) override {
    // The first generation has no population yet: samples of the space.
    if (population.empty()) return collect_unseen(count, seen, [&] { return space_.sample(rng); });
    const SubnetConfig& best = population.front().subnet;  // sorted best first
    return collect_unseen(count, seen, [&] { return mutate(space_, best, /*rate=*/0.2, rng); });
  }

 private:
  const ElasticSpace& space_;
};

void register_hill_climb_strategy(Registry<StrategyType>& registry) {
  registry.add("hill_climb",
               {parse_no_strategy_options,                  // no options: only `type` in its block
                [](const StrategyOptions&, YAML::Node&) {},  // so nothing to write back either
                [](const ElasticSpace& space, const StrategyOptions&) { return std::make_unique<HillClimb>(space); }},
               "neighbours of the best subnet so far (docs/extending.md)");
}

}  // namespace cgsr
