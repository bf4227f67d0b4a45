// The subnet search: genetic operators inside an elastic space, the Pareto tools, the generation
// loop with resume and failure policies (driven through the Evaluator interface by a scoring of
// each subnet from its real graph), and the inference evaluator on a rendered scene.
#include <gtest/gtest.h>

#include <cmath>

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
#include "tests/support/elastic_options.h"
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
  static const auto dir = test::scratch_dir("test-search");
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

// A latency table measured once per shape, on few subnets: what the tests need is its structure.
LatencyTableOptions quick_latency_table() {
  LatencyTableOptions latency;
  latency.calibration_subnets = 2;
  latency.check_subnets = 1;
  latency.runs = 1;
  latency.subnet_runs = 1;
  return latency;
}

// Two 12-pixel crops (2 of margin) of each of two frames.
ValidationCropOptions small_crops() {
  ValidationCropOptions crops;
  crops.frames = 2;
  crops.crops_per_frame = 2;
  crops.size = 12;
  crops.margin = 2;
  return crops;
}

SearchOptions small_search(const std::string& strategy = "evolution") {
  SearchOptions o;
  o.strategy.type = strategy;
  o.population = 12;
  o.generations = 5;
  return o;
}
}  // namespace

TEST(GeneticOperators, StayInsideTheSpace) {
  const ElasticSpace space(elastic_pan(), test::elastic_options(4, 0.25, 2));
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

TEST(GeneticOperators, MutateAndCrossPrecisions) {
  ElasticOptions options = test::elastic_options(4, 0.25, 2);
  options.precisions = {Precision::Fp32, Precision::Bf16, Precision::Int8};
  const ElasticSpace space(elastic_pan(), options);
  std::mt19937_64 rng(4);
  SubnetConfig a = space.full(), b = space.full();
  b.precision = Precision::Int8;
  std::set<Precision> mutated, crossed;
  for (int i = 0; i < 60; ++i) {
    const SubnetConfig m = mutate(space, a, 1.0, rng);
    EXPECT_NE(m.precision, Precision::Fp32);  // at rate 1 the precision always changes
    mutated.insert(m.precision);
    crossed.insert(crossover(space, a, b, rng).precision);
  }
  EXPECT_EQ(mutated, (std::set<Precision>{Precision::Bf16, Precision::Int8}));
  EXPECT_EQ(crossed, (std::set<Precision>{Precision::Fp32, Precision::Int8}));  // one parent's or the other's
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
  const ElasticSpace space(spec, test::elastic_options(4, 0.25, 2));
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

  // Checked by measurement: a machine on which every subnet runs 20% slower than predicted. The
  // pick is the best whose measured latency fits, found by bisection, not the predicted pick.
  const double widest = r.front.back().score.latency_ms;
  int timings = 0;
  const auto slower = [&](const Candidate& c) {
    ++timings;
    return 1.2 * c.score.latency_ms;
  };
  const MeasuredPick m = pick_measured(r.front, widest, widest, slower);
  int best_fitting = -1;
  for (size_t i = 0; i < r.front.size(); ++i)
    if (1.2 * r.front[i].score.latency_ms <= widest) best_fitting = static_cast<int>(i);
  ASSERT_GT(best_fitting, 0);  // the front spans more than 20% of latency
  EXPECT_TRUE(m.fits);
  EXPECT_EQ(m.pick.key, r.front[best_fitting].key);
  EXPECT_NE(m.pick.key, pick_within(r.front, widest).key);
  EXPECT_DOUBLE_EQ(m.measured, 1.2 * m.pick.score.latency_ms);
  EXPECT_EQ(static_cast<int>(m.timed.size()), timings);
  EXPECT_LE(timings, static_cast<int>(std::ceil(std::log2(r.front.size() + 1.0))));
  // Nothing fits: the fastest subnet, flagged.
  const MeasuredPick none = pick_measured(r.front, widest, 0, slower);
  EXPECT_FALSE(none.fits);
  EXPECT_EQ(none.pick.key, r.front.front().key);
}

TEST(SearchLoop, EvolutionFindsABetterFrontThanRandomSearchAtAsManyEvaluations) {
  const ArchSpec spec = elastic_pan(6);
  const ElasticSpace space(spec, test::elastic_options(4, 0.25, 2));
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
  const ElasticSpace space(spec, test::elastic_options(4, 0.25, 2));
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
  const ElasticSpace space(spec, test::elastic_options(4, 0.25, 2));
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
  const ElasticSpace space(spec, test::elastic_options(4, 0.25, 1));
  const LatencyTableOptions latency = quick_latency_table();
  const LatencyTable table = measure_latency_table(*net, space, 32, 24, latency);
  const ValidationCropOptions crops = small_crops();
  InferenceEvaluator evaluator(net, data, crops, {{Precision::Fp32, table}});
  const int frames = std::min<int>(2, static_cast<int>(data.frames(Split::Val).size()));
  EXPECT_EQ(evaluator.crops(), 2 * frames);
  const SubnetScore full = evaluator.evaluate(space.full()), small = evaluator.evaluate(space.smallest());
  EXPECT_TRUE(std::isfinite(full.psnr) && std::isfinite(small.psnr));
  EXPECT_GT(full.macs, small.macs);
  EXPECT_GT(full.latency_ms, 0);
  // Deterministic: the same subnet scores the same.
  EXPECT_EQ(evaluator.evaluate(space.smallest()).psnr, small.psnr);
}

TEST(InferenceEvaluator, ScoresAnInt8SubnetOnTheFusedPathWithItsOwnLatencyTable) {
  seed_everything(6);
  const Dataset data = Dataset::open(test::tiny_data());
  ArchSpec spec = elastic_pan(2);
  SRNetwork net(spec);
  net->eval();
  ElasticOptions options = test::elastic_options(4, 0.25, 1);
  options.precisions = {Precision::Fp32, Precision::Int8};
  const ElasticSpace space(spec, options);
  const LatencyTableOptions latency = quick_latency_table();
  std::map<Precision, LatencyTable> tables;
  for (Precision p : options.precisions) tables[p] = measure_latency_table(*net, space, 32, 24, latency, p);
  // The int8 table times the inner convolutions in int8 and the wide first and last in float32.
  int int8_keys = 0;
  for (const auto& [key, ms] : tables.at(Precision::Int8).conv_ms)
    int8_keys += key.size() > 5 && key.substr(key.size() - 5) == "_int8";
  EXPECT_GT(int8_keys, 0);
  EXPECT_LT(int8_keys, static_cast<int>(tables.at(Precision::Int8).conv_ms.size()));
  for (const auto& [key, ms] : tables.at(Precision::Fp32).conv_ms) EXPECT_EQ(key.find("int8"), std::string::npos);
  // Both kept in a provenance, read back by precision; a table under another's key is refused.
  nlohmann::ordered_json extra;
  for (const auto& [p, t] : tables) extra[latency_table_key(p)] = to_json(t);
  const auto back = latency_tables_from(extra, "model.cgsr");
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back.at(Precision::Int8).precision, Precision::Int8);
  EXPECT_EQ(back.at(Precision::Int8).conv_ms, tables.at(Precision::Int8).conv_ms);
  extra["latency_table_bf16"] = extra["latency_table_int8"];
  EXPECT_THROW(latency_tables_from(extra, "model.cgsr"), Error);
  const ValidationCropOptions crops = small_crops();
  InferenceEvaluator evaluator(net, data, crops, tables);
  SubnetConfig int8 = space.smallest();
  int8.precision = Precision::Int8;
  const SubnetScore f = evaluator.evaluate(space.smallest()), q = evaluator.evaluate(int8);
  // The same subnet: its int8 output is close to float32's, not equal (it ran quantized).
  EXPECT_NE(q.psnr, f.psnr);
  EXPECT_NEAR(q.psnr, f.psnr, 0.5);
  EXPECT_EQ(q.macs, f.macs);
  EXPECT_EQ(q.latency_ms, tables.at(Precision::Int8).predict(subnet_graph(*net, int8)));
  EXPECT_EQ(evaluator.evaluate(int8).psnr, q.psnr);  // calibration and scoring are deterministic
  // A precision without a table is an error naming the subnet.
  SubnetConfig bf16 = int8;
  bf16.precision = Precision::Bf16;
  try {
    evaluator.evaluate(bf16);
    FAIL() << "scored without a bf16 latency table";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("|bf16"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("no bf16 latency table"), std::string::npos) << e.what();
  }
}
