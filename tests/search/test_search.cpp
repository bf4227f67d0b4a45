// The subnet search: genetic operators inside an elastic space, the Pareto tools, the generation
// loop with resume and failure policies (driven through the Evaluator interface by a scoring of
// each subnet from its real graph), and the inference evaluator on a rendered scene.
#include <gtest/gtest.h>

#include <filesystem>
#include <random>
#include <set>

#include "core/error.h"
#include "core/pareto.h"
#include "core/runtime.h"
#include "models/backbone_registry.h"
#include "models/complexity.h"
#include "models/elastic.h"
#include "search/genetic_operators.h"
#include "search/search_loop.h"
#include "search/subnet_evaluator.h"
#include "tests/support/tiny_data.h"

using namespace cgsr;

namespace {
ArchSpec elastic_pan(int blocks = 4) {
  ArchSpec spec;
  spec.backbone = "pan";
  spec.scale = 2;
  spec.blocks = blocks;
  spec.rit.enabled = true;
  spec.rit.source = RitSource::HrUnshuffleHrFuse;
  return resolve_spec(spec);
}

std::filesystem::path temp_file(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("cgsr_test_search_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto path = dir / name;
  std::filesystem::remove(path);
  return path;
}

// Scores a subnet from its real graph: latency is its MAC count, and quality rises with the log of
// each layer group's width, weighted by how much that group matters (some much more than others,
// as in a real network), and a little with depth. Deterministic, like the real evaluator must be.
// `diverging` keys fail to score (a non-finite output).
class ScoringEvaluator : public Evaluator {
 public:
  explicit ScoringEvaluator(const ArchSpec& spec) : net_(spec) {}
  SubnetScore evaluate(const SubnetConfig& sub) override {
    ++calls_;
    if (diverging.count(subnet_key(sub))) throw Error("subnet " + subnet_key(sub), "its output is not finite");
    const Complexity c = complexity(subnet_graph(*net_, sub), 32, 24);
    SubnetScore s;
    s.macs = c.macs;
    s.params = c.params;
    s.latency_ms = static_cast<double>(c.macs) * 1e-6;
    s.psnr = 30 + 0.05 * static_cast<double>(sub.blocks.size());
    for (const auto& [group, width] : sub.widths) {
      const auto block = parse_block_group(group);
      if (block && !std::binary_search(sub.blocks.begin(), sub.blocks.end(), block->first)) continue;
      const double weight = static_cast<double>(std::hash<std::string>{}(group) % 100) / 100.0;
      s.psnr += weight * weight * std::log(static_cast<double>(width));
    }
    return s;
  }
  int calls() const { return calls_; }
  std::set<std::string> diverging;

 private:
  SRNetwork net_;
  int calls_ = 0;
};

SearchOptions small_search(const std::string& strategy = "evolution") {
  SearchOptions o;
  o.strategy.type = strategy;
  o.population = 12;
  o.generations = 5;
  return o;
}
}  // namespace

TEST(GeneticOperators, StayInsideTheSpace) {
  const ElasticSpace space(elastic_pan(), ElasticOptions{4, 0.25, 2});
  std::mt19937_64 rng(3);
  std::set<std::string> keys;
  for (int i = 0; i < 200; ++i) {
    const SubnetConfig a = space.sample(rng), b = space.sample(rng);
    const SubnetConfig m = mutate(space, a, 0.3, rng), c = crossover(space, a, b, rng);
    EXPECT_TRUE(space.contains(m)) << subnet_key(m);
    EXPECT_TRUE(space.contains(c)) << subnet_key(c);
    keys.insert(subnet_key(m));
  }
  EXPECT_GT(keys.size(), 150u);  // mutation explores
  // A rate of 0 changes nothing; crossover of a subnet with itself gives it back.
  const SubnetConfig a = space.sample(rng);
  EXPECT_EQ(subnet_key(mutate(space, a, 0.0, rng)), subnet_key(a));
  EXPECT_EQ(subnet_key(crossover(space, a, a, rng)), subnet_key(a));
}

TEST(Pareto, RanksCrowdingAndHypervolume) {
  // cost, quality: 0 and 1 on the front, 2 behind 0, 3 behind everything.
  const std::vector<double> cost = {1, 2, 1.5, 3}, quality = {1, 2, 0.5, 0};
  EXPECT_EQ(pareto_ranks(cost, quality), (std::vector<int>{0, 0, 1, 2}));
  EXPECT_EQ(pareto_front(cost, quality), (std::vector<size_t>{0, 1}));
  const auto d = crowding_distance({0, 1}, cost, quality);
  EXPECT_TRUE(std::isinf(d[0]) && std::isinf(d[1]));
  // Dominated area against (4, 0): [1,2) x 1 + [2,4) x 2 = 5; behind points add nothing.
  EXPECT_DOUBLE_EQ(hypervolume(cost, quality, 4, 0), 5.0);
  EXPECT_DOUBLE_EQ(hypervolume({1, 2}, {1, 2}, 4, 0), 5.0);
  EXPECT_DOUBLE_EQ(hypervolume({5}, {1}, 4, 0), 0.0);
}

TEST(SearchLoop, EvolutionScoresEverySubnetOnceAndBuildsAFront) {
  const ArchSpec spec = elastic_pan();
  const ElasticSpace space(spec, ElasticOptions{4, 0.25, 2});
  ScoringEvaluator evaluator(spec);
  SearchHistory history(temp_file("evolution.jsonl"), false);
  seed_everything(1);
  const SearchResult r = run_search(space, evaluator, history, small_search(), "evolution");
  EXPECT_EQ(r.generations_run, 5);
  EXPECT_EQ(static_cast<int>(r.evaluated.size()), 60);
  EXPECT_EQ(evaluator.calls(), 60);
  std::set<std::string> keys;
  for (const auto& c : r.evaluated) keys.insert(c.key);
  EXPECT_EQ(keys.size(), r.evaluated.size());
  ASSERT_FALSE(r.front.empty());
  for (size_t i = 1; i < r.front.size(); ++i) {
    EXPECT_GT(r.front[i].score.latency_ms, r.front[i - 1].score.latency_ms);
    EXPECT_GT(r.front[i].quality, r.front[i - 1].quality);
  }
  // The pick is the best within the budget, or the fastest when nothing fits.
  const double budget = r.front[r.front.size() / 2].score.latency_ms;
  EXPECT_EQ(pick_within(r.front, budget).key, r.front[r.front.size() / 2].key);
  EXPECT_EQ(pick_within(r.front, 0).key, r.front.front().key);
}

TEST(SearchLoop, EvolutionFindsABetterFrontThanRandomSearchAtAsManyEvaluations) {
  const ArchSpec spec = elastic_pan(6);
  const ElasticSpace space(spec, ElasticOptions{4, 0.25, 2});
  ScoringEvaluator evaluator(spec);
  seed_everything(2);
  SearchOptions o = small_search();
  o.generations = 8;
  SearchHistory evolution_history(temp_file("e.jsonl"), false), random_history(temp_file("r.jsonl"), false);
  const SearchResult e = run_search(space, evaluator, evolution_history, o, "evolution");
  const SearchResult r = run_search(space, evaluator, random_history, small_search("random"), "random");
  double worst = 1e9;
  for (const auto* run : {&e, &r})
    for (const auto& c : run->evaluated) worst = std::min(worst, c.quality);
  const double latency_ref = evaluator.evaluate(space.full()).latency_ms;
  EXPECT_GT(front_hypervolume(e.front, latency_ref, worst), front_hypervolume(r.front, latency_ref, worst));
}

TEST(SearchLoop, AResumedSearchReachesTheSameResult) {
  const ArchSpec spec = elastic_pan();
  const ElasticSpace space(spec, ElasticOptions{4, 0.25, 2});
  seed_everything(4);
  ScoringEvaluator whole(spec);
  SearchHistory whole_history(temp_file("whole.jsonl"), false);
  const SearchResult reference = run_search(space, whole, whole_history, small_search(), "evolution");

  // The first run stops after 3 generations (a kill between generations); the second resumes it.
  const auto path = temp_file("resumed.jsonl");
  {
    ScoringEvaluator first(spec);
    SearchHistory history(path, false);
    SearchOptions o = small_search();
    o.generations = 3;
    run_search(space, first, history, o, "evolution");
  }
  EXPECT_THROW(SearchHistory(path, false), Error);  // never overwritten by accident
  ScoringEvaluator second(spec);
  SearchHistory history(path, true);
  const SearchResult resumed = run_search(space, second, history, small_search(), "evolution");
  EXPECT_EQ(second.calls(), 24);  // only the two generations left
  ASSERT_EQ(resumed.front.size(), reference.front.size());
  for (size_t i = 0; i < reference.front.size(); ++i) EXPECT_EQ(resumed.front[i].key, reference.front[i].key);
}

TEST(SearchLoop, AFailingSubnetFollowsTheFailurePolicy) {
  const ArchSpec spec = elastic_pan();
  const ElasticSpace space(spec, ElasticOptions{4, 0.25, 2});
  // Which subnets the first generation proposes: make one of them diverge.
  seed_everything(5);
  std::string victim;
  {
    ScoringEvaluator probe(spec);
    SearchHistory history(temp_file("probe.jsonl"), false);
    SearchOptions o = small_search();
    o.generations = 1;
    victim = run_search(space, probe, history, o, "evolution").evaluated.at(3).key;
  }
  for (const FailurePolicy policy : {FailurePolicy::Worst, FailurePolicy::Retry, FailurePolicy::Abort}) {
    SCOPED_TRACE(enum_name(policy));
    seed_everything(5);
    ScoringEvaluator evaluator(spec);
    evaluator.diverging = {victim};
    const auto path = temp_file("fail_" + enum_name(policy) + ".jsonl");
    SearchHistory history(path, false);
    SearchOptions o = small_search();
    o.on_failure.score = policy;
    if (policy == FailurePolicy::Abort) {
      EXPECT_THROW(run_search(space, evaluator, history, o, "evolution"), Error);
      continue;
    }
    const SearchResult r = run_search(space, evaluator, history, o, "evolution");
    EXPECT_EQ(r.failures, 1);
    EXPECT_EQ(evaluator.calls(), 60 + (policy == FailurePolicy::Retry ? 1 : 0));
    for (const auto& c : r.front) EXPECT_NE(c.key, victim);
    // The history remembers the failure too: a resumed search scores nothing again.
    seed_everything(5);
    ScoringEvaluator again(spec);
    SearchHistory reread(path, true);
    EXPECT_EQ(run_search(space, again, reread, o, "evolution").failures, 1);
    EXPECT_EQ(again.calls(), 0);
  }
}

TEST(InferenceEvaluator, ScoresSubnetsOfARealNetworkOnRenderedCrops) {
  seed_everything(6);
  const Dataset data = Dataset::open(test::tiny_data());
  ArchSpec spec = elastic_pan(2);
  SRNetwork net(spec);
  net->eval();
  const ElasticSpace space(spec, ElasticOptions{4, 0.25, 1});
  LatencyTableOptions latency;
  latency.calibration_subnets = 2;
  latency.check_subnets = 1;
  latency.runs = 1;
  latency.subnet_runs = 1;
  const LatencyTable table = measure_latency_table(*net, space, 32, 24, latency);
  ValidationCropOptions crops;
  crops.frames = 2;
  crops.crops_per_frame = 2;
  crops.size = 12;
  crops.margin = 2;
  InferenceEvaluator evaluator(net, data, crops, table);
  const int frames = std::min<int>(2, static_cast<int>(data.frames(Split::Val).size()));
  EXPECT_EQ(evaluator.crops(), 2 * frames);
  const SubnetScore full = evaluator.evaluate(space.full()), small = evaluator.evaluate(space.smallest());
  EXPECT_TRUE(std::isfinite(full.psnr) && std::isfinite(small.psnr));
  EXPECT_GT(full.macs, small.macs);
  EXPECT_GT(full.latency_ms, 0);
  // Deterministic: the same subnet scores the same.
  EXPECT_EQ(evaluator.evaluate(space.smallest()).psnr, small.psnr);
}
