// The shapes of the stage configs of `cgsr run`: the search options at the top of a search
// config, the enhance stage's rit and geometry and the elastic stage's keys at their tops, and
// the older nested enhance block still read.
#include <gtest/gtest.h>

#include <unistd.h>

#include "core/config.h"
#include "models/model_file.h"
#include "pipeline/search_stage.h"
#include "pipeline/train_stage.h"
#include "tests/support/scratch_dir.h"

using namespace cgsr;

namespace {
template <class T>
T parse(const std::string& yaml, const config::Schema<T>& schema) {
  return config::parse_document(config::Document::parse(yaml, "stage.yaml"), schema);
}
}  // namespace

TEST(StageConfigs, SearchOptionsSitAtTheTopWithTheStrategyInItsOwnBlock) {
  const auto o = parse<SearchCommandOptions>(
      "model: e.cgsr\ndata: d\nstrategy: {type: evolution, mutation_rate: 0.25}\npopulation: 4\n"
      "on_failure: {score: retry}\nfinal: {schedule: {steps: 3}}\n",
      search_command_schema());
  EXPECT_EQ(o.search.population, 4);
  EXPECT_DOUBLE_EQ(o.search.strategy.evolution.mutation_rate, 0.25);
  EXPECT_EQ(o.search.on_failure.score, FailurePolicy::Retry);
  EXPECT_EQ(o.final.schedule.steps, 3);
  EXPECT_EQ(o.baseline, "random");
  EXPECT_THROW(parse<SearchCommandOptions>("model: e\ndata: d\nbaseline: nope\n", search_command_schema()), Error);
  EXPECT_THROW(parse<SearchCommandOptions>("model: e\ndata: d\non_failure: {score: sometimes}\n",
                                           search_command_schema()),
               Error);
}

TEST(StageConfigs, TheElasticStageTakesItsElasticKeysAtItsTop) {
  const auto flat = parse<TrainOptions>("data: d\nsampled: 3\nspace: {quantum: 8}\n", elastic_stage_schema());
  EXPECT_EQ(flat.elastic.sampled, 3);
  EXPECT_EQ(flat.elastic.space.quantum, 8);
  EXPECT_THROW(parse<TrainOptions>("data: d\nenabled: true\n", elastic_stage_schema()), Error);
}

// elastic.from_scratch keeps the model's architecture and drops its weights: without it the
// elastic network computes the model's function (its channels only reordered), with it another.
TEST(StageConfigs, AnElasticStageFromScratchStartsFromFreshWeights) {
  torch::manual_seed(5);
  const auto file = test::scratch_dir("stage-configs") / "trained.cgsr";
  SRNetwork trained(resolve_spec(default_spec("pan", 2)));
  save_model(file, *trained);
  TrainOptions o = parse<TrainOptions>("data: d\nmodel: " + file.string() + "\n", elastic_stage_schema());
  o.elastic.enabled = true;
  EXPECT_FALSE(o.elastic.from_scratch);
  const auto color = torch::rand({1, 3, 10, 12});
  torch::NoGradGuard no_grad;
  const auto expected = trained->forward(color);
  SRNetwork inherited = starting_network(o);
  EXPECT_TRUE(torch::allclose(inherited->forward(color), expected, 1e-5, 1e-5));
  o = parse<TrainOptions>("data: d\nmodel: " + file.string() + "\nfrom_scratch: true\n", elastic_stage_schema());
  o.elastic.enabled = true;
  ASSERT_TRUE(o.elastic.from_scratch);
  SRNetwork fresh = starting_network(o);
  EXPECT_EQ(fresh->spec(), inherited->spec());
  EXPECT_GT((fresh->forward(color) - expected).abs().max().item<float>(), 1e-3f);
  std::filesystem::remove(file);
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
