// The shapes of the stage configs of `cgsr run`: the search options at the top of a search
// config, the enhance stage's rit and geometry at its top, the older nested shapes still read,
// and the search stage's cache form (the shape its stage hash has always been made of).
#include <gtest/gtest.h>

#include "core/config.h"
#include "pipeline/distributed_run.h"
#include "pipeline/search_stage.h"
#include "pipeline/train_stage.h"

using namespace cgsr;

namespace {
template <class T>
T parse(const std::string& yaml, const config::Schema<T>& schema) {
  return config::parse_document(config::Document::parse(yaml, "stage.yaml"), schema);
}
std::vector<std::string> keys_of(const YAML::Node& map) {
  std::vector<std::string> keys;
  for (const auto& kv : map) keys.push_back(kv.first.Scalar());
  return keys;
}
}  // namespace

TEST(StageConfigs, SearchOptionsSitAtTheTopAndTheFormerSearchBlockReadsTheSame) {
  const auto flat = parse<SearchCommandOptions>(
      "parent: p.cgsr\ndata: d\nstrategy: {type: evolution, mutation_rate: 0.25}\npopulation: 4\nfinal: {steps: 3}\n",
      search_command_schema());
  const auto nested = parse<SearchCommandOptions>(
      "parent: p.cgsr\ndata: d\nsearch:\n  strategy: evolution\n  population: 4\n  operators: {mutation_rate: 0.25}\n"
      "final: {steps: 3}\n",
      search_command_schema());
  const YAML::Node emitted = search_command_schema().emit(flat);
  EXPECT_EQ(config::to_yaml(emitted), config::to_yaml(search_command_schema().emit(nested)));
  EXPECT_EQ(flat.search.population, 4);
  EXPECT_DOUBLE_EQ(flat.search.strategy.evolution.mutation_rate, 0.25);

  // The cache form is the former shape, key for key (what `cgsr search` emitted before), once
  // `cgsr run` leaves out the distributed block, which no stage hash includes.
  const YAML::Node cached = without_distribution(search_config_cache_form(emitted));
  EXPECT_EQ(keys_of(cached), (std::vector<std::string>{"parent", "data", "search", "candidate", "final", "name",
                                                        "resume", "seed", "threads"}));
  EXPECT_EQ(keys_of(cached["search"]),
            (std::vector<std::string>{"strategy", "population", "selection_ratio", "generations", "min_candidates",
                                      "tolerance_db", "space", "operators", "fitness"}));
  EXPECT_EQ(cached["search"]["strategy"].Scalar(), "evolution");
  EXPECT_EQ(config::to_yaml(cached["search"]["operators"]),
            "initial_spread: 0.5\nmutation_rate: 0.25\ncrossover_rate: 0.5\n");
}

TEST(StageConfigs, TheEnhanceStageTakesRitAndGeometryAtItsTop) {
  const auto flat = parse<TrainOptions>("data: d\nrit: {width: 8, source: hr_pooled}\ngeometry: {enabled: false}\n",
                                        enhance_stage_schema());
  const auto nested = parse<TrainOptions>(
      "data: d\nenhance: {enabled: true, rit: {width: 8, source: hr_pooled}, geometry: {enabled: false}}\n",
      enhance_stage_schema());
  EXPECT_EQ(flat.enhance.rit.width, 8);
  EXPECT_FALSE(flat.enhance.geometry.enabled);
  // Both are recorded (and hashed) as the same `cgsr train` config.
  EXPECT_EQ(config::to_yaml(train_schema().emit(flat)), config::to_yaml(train_schema().emit(nested)));
}
