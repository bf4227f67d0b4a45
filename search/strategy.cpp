#include "search/strategy.h"

#include <algorithm>
#include <set>

#include "search/genetic_operators.h"

namespace cgsr {

config::Schema<EvolutionOptions> evolution_schema() {
  config::Schema<EvolutionOptions> s;
  s.field("mutation_rate", &EvolutionOptions::mutation_rate, "per-gene mutation rate").range(0, 1);
  s.field("crossover_rate", &EvolutionOptions::crossover_rate, "share of children made by crossover").range(0, 1);
  return s;
}

std::vector<SubnetConfig> collect_unseen(int count, const std::function<bool(const std::string&)>& seen,
                                         const std::function<SubnetConfig()>& draw) {
  std::vector<SubnetConfig> out;
  std::set<std::string> taken;
  const int max_attempts = 50 * std::max(1, count);
  for (int attempt = 0; attempt < max_attempts && static_cast<int>(out.size()) < count; ++attempt) {
    SubnetConfig sub = draw();
    const std::string key = subnet_key(sub);
    if (seen(key) || !taken.insert(key).second) continue;
    out.push_back(std::move(sub));
  }
  return out;
}

namespace {
class Evolution : public SearchStrategy {
 public:
  Evolution(const ElasticSpace& space, EvolutionOptions options) : space_(space), options_(options) {}
  std::vector<SubnetConfig> propose(const std::vector<Candidate>& population, int count,
                                    const std::function<bool(const std::string&)>& seen,
                                    std::mt19937_64& rng) override {
    if (population.empty()) return collect_unseen(count, seen, [&] { return space_.sample_candidate(rng); });
    std::uniform_real_distribution<double> u(0, 1);
    std::uniform_int_distribution<size_t> pick(0, population.size() - 1);
    // Binary tournament: the population is sorted best first, so the lower index wins.
    const auto parent = [&]() -> const SubnetConfig& { return population[std::min(pick(rng), pick(rng))].subnet; };
    return collect_unseen(count, seen, [&] {
      if (population.size() >= 2 && u(rng) < options_.crossover_rate)
        return mutate(space_, crossover(space_, parent(), parent(), rng), options_.mutation_rate, rng);
      return mutate(space_, parent(), options_.mutation_rate, rng);
    });
  }

 private:
  const ElasticSpace& space_;
  EvolutionOptions options_;
};

class RandomSearch : public SearchStrategy {
 public:
  explicit RandomSearch(const ElasticSpace& space) : space_(space) {}
  std::vector<SubnetConfig> propose(const std::vector<Candidate>&, int count,
                                    const std::function<bool(const std::string&)>& seen,
                                    std::mt19937_64& rng) override {
    return collect_unseen(count, seen, [&] { return space_.sample_candidate(rng); });
  }

 private:
  const ElasticSpace& space_;
};
}  // namespace

void parse_no_strategy_options(const YAML::Node& block, StrategyOptions& options, const config::Cursor& at) {
  for (const auto& kv : block)
    if (!kv.first.IsScalar() || kv.first.Scalar() != "type")
      at.fail(kv.first, "the " + options.type + " strategy has no options; only 'type' belongs here");
}

Registry<StrategyType>& strategy_registry() {
  static Registry<StrategyType> registry = [] {
    Registry<StrategyType> r("search strategy");
    r.add("evolution",
          {[](const YAML::Node& block, StrategyOptions& o, const config::Cursor& at) {
             evolution_schema().parse(block, o.evolution, at, {"type"});
           },
           [](const StrategyOptions& o, YAML::Node& block) {
             for (const auto& kv : evolution_schema().emit(o.evolution)) block[kv.first] = kv.second;
           },
           [](const ElasticSpace& space, const StrategyOptions& o) {
             return std::make_unique<Evolution>(space, o.evolution);
           }},
          "NSGA-II: tournament on Pareto rank and crowding, crossover and mutation (CGSR)");
    r.add("random",
          {parse_no_strategy_options, [](const StrategyOptions&, YAML::Node&) {},
           [](const ElasticSpace& space, const StrategyOptions&) { return std::make_unique<RandomSearch>(space); }},
          "uniform samples of the search space (baseline)");
    return r;
  }();
  return registry;
}

}  // namespace cgsr

namespace cgsr::config {

StrategyOptions Codec<StrategyOptions>::decode(const YAML::Node& n, const Cursor& at) {
  const auto& registry = strategy_registry();
  const auto known_type = [&](const YAML::Node& name, const Cursor& where) {
    const std::string type = Codec<std::string>::decode(name, where);
    if (!registry.contains(type))
      where.fail(name, "unknown " + registry.kind() + " '" + type + "'" + did_you_mean(type, registry.names()) +
                           "; valid: " + join(registry.names()));
    return type;
  };
  StrategyOptions o;
  if (n.IsScalar()) {
    o.type = known_type(n, at);
    return o;
  }
  if (!n.IsMap()) at.fail(n, "expected a strategy name or a block {type: Name, ...}, got " + detail::describe(n));
  if (!n["type"]) at.fail(n, "missing required key 'type' (one of: " + join(registry.names()) + ")");
  o.type = known_type(n["type"], at.child("type"));
  registry.get(o.type).parse_options(n, o, at);
  return o;
}

YAML::Node Codec<StrategyOptions>::encode(const StrategyOptions& o) {
  YAML::Node block(YAML::NodeType::Map);
  block["type"] = o.type;
  strategy_registry().get(o.type).emit_options(o, block);
  return block;
}

}  // namespace cgsr::config
