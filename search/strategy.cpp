#include <set>

#include "search/strategy.h"

namespace cgsr {

config::Schema<StrategyOptions> strategy_schema() {
  config::Schema<StrategyOptions> s;
  s.field("initial_spread", &StrategyOptions::initial_spread, "per-gene mutation rate of the first generation")
      .range(0, 1);
  s.field("mutation_rate", &StrategyOptions::mutation_rate, "per-gene mutation rate").range(0, 1);
  s.field("crossover_rate", &StrategyOptions::crossover_rate, "share of children made by crossover").range(0, 1);
  return s;
}

namespace {
// Draws specs until `count` new ones are found or attempts run out (the space is exhausted).
std::vector<ArchSpec> collect(int count, const SearchSpace& space, const std::function<bool(const std::string&)>& seen,
                              const std::function<ArchSpec()>& draw) {
  std::vector<ArchSpec> out;
  std::set<std::string> taken;
  const int max_attempts = 50 * std::max(1, count);
  for (int attempt = 0; attempt < max_attempts && static_cast<int>(out.size()) < count; ++attempt) {
    ArchSpec spec = draw();
    if (!space.contains(spec)) continue;
    const std::string key = SearchSpace::key(spec);
    if (seen(key) || !taken.insert(key).second) continue;
    out.push_back(std::move(spec));
  }
  return out;
}

class Evolution : public SearchStrategy {
 public:
  Evolution(const SearchSpace& space, StrategyOptions options) : space_(space), options_(options) {}
  std::vector<ArchSpec> propose(const std::vector<Candidate>& survivors, int count,
                                const std::function<bool(const std::string&)>& seen, std::mt19937_64& rng) override {
    std::uniform_real_distribution<double> u(0, 1);
    return collect(count, space_, seen, [&] {
      if (survivors.empty()) return space_.mutate(space_.parent(), options_.initial_spread, rng);
      std::uniform_int_distribution<size_t> pick(0, survivors.size() - 1);
      if (survivors.size() >= 2 && u(rng) < options_.crossover_rate) {
        const size_t a = pick(rng);
        size_t b = pick(rng);
        while (b == a) b = pick(rng);
        return space_.mutate(space_.crossover(survivors[a].spec, survivors[b].spec, rng), options_.mutation_rate, rng);
      }
      return space_.mutate(survivors[pick(rng)].spec, options_.mutation_rate, rng);
    });
  }

 private:
  const SearchSpace& space_;
  StrategyOptions options_;
};

class RandomSearch : public SearchStrategy {
 public:
  explicit RandomSearch(const SearchSpace& space) : space_(space) {}
  std::vector<ArchSpec> propose(const std::vector<Candidate>&, int count,
                                const std::function<bool(const std::string&)>& seen, std::mt19937_64& rng) override {
    return collect(count, space_, seen, [&] { return space_.sample(rng); });
  }

 private:
  const SearchSpace& space_;
};
}  // namespace

const Registry<StrategyFactory>& strategy_registry() {
  static const Registry<StrategyFactory> registry = [] {
    Registry<StrategyFactory> r("search strategy");
    r.add("evolution",
          [](const SearchSpace& space, const StrategyOptions& o) { return std::make_unique<Evolution>(space, o); },
          "mutation and crossover of the survivors (CGSR)");
    r.add("random", [](const SearchSpace& space, const StrategyOptions&) { return std::make_unique<RandomSearch>(space); },
          "uniform samples of the search space (baseline)");
    return r;
  }();
  return registry;
}

}  // namespace cgsr
