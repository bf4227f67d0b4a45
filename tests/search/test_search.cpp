// The search: its space and operators on real specs, and the generation loop, the pick rule and
// resume, driven through the Evaluator interface by a deterministic scoring of specs.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>

#include "core/error.h"
#include "core/runtime.h"
#include "models/backbone_registry.h"
#include "models/sr_network.h"
#include "search/search_loop.h"
#include "tests/support/cli_runner.h"

using namespace cgsr;

namespace {
ArchSpec enhanced_pan(int blocks = 4) {
  ArchSpec spec;
  spec.backbone = "pan";
  spec.scale = 2;
  spec.blocks = blocks;
  spec.rit.enabled = true;
  spec.geometry.enabled = true;
  return resolve_spec(spec);
}

// Scores a spec from its real parameter count: quality falls off as the network shrinks, and
// RIT channels help (depth and edge most). Deterministic, like the real evaluator must be.
class ScoringEvaluator : public Evaluator {
 public:
  explicit ScoringEvaluator(ArchSpec parent, int fail_after = -1) : parent_(std::move(parent)), fail_after_(fail_after) {}
  CandidateScore evaluate(const ArchSpec& spec) override {
    if (fail_after_ >= 0 && calls_ >= fail_after_) throw Error("evaluator", "killed");
    ++calls_;
    return score(spec);
  }
  CandidateScore evaluate_parent() override { return score(parent_); }
  int calls() const { return calls_; }

 private:
  CandidateScore score(const ArchSpec& spec) const {
    const double params = static_cast<double>(inference_parameter_count(*SRNetwork(spec)));
    const double parent_params = static_cast<double>(inference_parameter_count(*SRNetwork(parent_)));
    const double shrink = 1.0 - params / parent_params;
    double bonus = 0;
    for (const auto& c : spec.rit.channels) bonus += c == "depth" || c == "edge" ? 0.05 : 0.01;
    CandidateScore s;
    s.params = static_cast<int64_t>(params);
    s.macs = s.params * 1000;
    s.val_psnr = 33.0 + bonus - 3.0 * std::pow(std::max(0.0, shrink - 0.3), 2);
    s.image_loss = std::pow(10.0, -s.val_psnr / 10.0);
    s.geometry_loss = 0.01 * (1 + shrink);
    return s;
  }
  ArchSpec parent_;
  int fail_after_;
  int calls_ = 0;
};

SearchOptions small_search() {
  SearchOptions o;
  o.population = 6;
  o.selection_ratio = 0.5;
  o.generations = 3;
  o.tolerance_db = 0.05;
  return o;
}

std::filesystem::path history_path(const std::string& name) {
  return cgsr::test::scratch_dir("search-" + name) / "history.jsonl";
}
}  // namespace

TEST(SearchSpace, WidthChoicesAreQuantizedAndKeepTheParentWidth) {
  const SearchSpace space(enhanced_pan(), {});
  EXPECT_EQ(space.width_choices(40), (std::vector<int>{16, 24, 32, 40}));
  EXPECT_EQ(space.width_choices(20), (std::vector<int>{8, 16, 20}));
  EXPECT_EQ(space.width_choices(24), (std::vector<int>{8, 16, 24}));
}

TEST(SearchSpace, OperatorsStayInsideTheSpace) {
  seed_everything(3);
  const SearchSpace space(enhanced_pan(), {});
  auto rng = make_rng("test");
  ArchSpec a = space.parent(), b = space.parent();
  for (int i = 0; i < 30; ++i) {
    a = space.mutate(a, 0.3, rng);
    b = space.sample(rng);
    const ArchSpec c = space.crossover(a, b, rng);
    for (const ArchSpec* s : std::vector<const ArchSpec*>{&a, &b, &c}) {
      ASSERT_TRUE(space.contains(*s)) << spec_to_yaml(*s);
      EXPECT_LE(s->blocks, space.parent().blocks);
      EXPECT_FALSE(s->rit.channels.empty());
    }
  }
  EXPECT_NE(SearchSpace::key(a), SearchSpace::key(space.parent()));
}

TEST(SearchSpace, RejectsWiderThanTheParent) {
  const SearchSpace space(enhanced_pan(), {});
  ArchSpec wide = space.parent();
  wide.widths.set("features", 48);
  EXPECT_FALSE(space.contains(wide));
}

// Parent blocks 1 and 3 matter least: shallower candidates keep the others, and each block gene
// stays with the parent block it belongs to through mutation, crossover and sampling.
TEST(SearchSpace, ShallowerCandidatesDropBlocksInTheGivenOrder) {
  const std::vector<int> order = {1, 3, 0, 2};
  const SearchSpace space(enhanced_pan(4), {}, order);
  const SearchSpace trailing(enhanced_pan(4), {});
  ArchSpec three = space.parent();
  three.blocks = 3;
  three.widths = GroupWidths();
  three = resolve_spec(three);
  EXPECT_EQ(space.parent_blocks(three), (std::vector<int>{0, 2, 3}));
  EXPECT_EQ(trailing.parent_blocks(three), (std::vector<int>{0, 1, 2}));
  three.blocks = 2;
  three.widths = GroupWidths();
  EXPECT_EQ(space.parent_blocks(resolve_spec(three)), (std::vector<int>{0, 2}));

  // Crossing a 4-block spec whose parent block 2 is narrowed with a 3-block one: a 3-block child
  // carries the narrow gene on its block 1 (parent block 2), never on its block 2 (parent block 3).
  ArchSpec marked = space.parent();
  marked.widths.set(block_group(2, "a"), 8);
  three.blocks = 3;
  three.widths = GroupWidths();
  three = resolve_spec(three);
  ASSERT_TRUE(space.contains(marked));
  ASSERT_TRUE(space.contains(three));
  auto rng = make_rng("block-genes");
  int carried = 0;
  for (int i = 0; i < 100; ++i) {
    const ArchSpec child = space.crossover(marked, three, rng);
    ASSERT_TRUE(space.contains(child)) << spec_to_yaml(child);
    const int on_parent_block_2 = child.blocks == 3 ? 1 : 2;
    for (int b = 0; b < child.blocks; ++b) {
      const int width = child.widths.at(block_group(b, "a"));
      if (b == on_parent_block_2) carried += width == 8;
      else EXPECT_EQ(width, 20) << "child block " << b << " of " << child.blocks;
    }
  }
  EXPECT_GT(carried, 0);
}

TEST(SearchLoop, PicksTheSmallestCandidateWithinTolerance) {
  Candidate parent;
  parent.score.val_psnr = 33.0;
  parent.score.params = 1000;
  std::vector<Candidate> cands(3);
  cands[0].score = {32.99, 0, 0, 0, 600, 0, {}, 0};  // within 0.05 dB
  cands[1].score = {32.90, 0, 0, 0, 300, 0, {}, 0};  // smaller but too lossy
  cands[2].score = {33.10, 0, 0, 0, 800, 0, {}, 0};
  SearchOptions o;
  bool is_parent = true;
  EXPECT_EQ(pick_candidate(parent, cands, o, &is_parent).score.params, 600);
  EXPECT_FALSE(is_parent);
  o.tolerance_db = 0.0;
  EXPECT_EQ(pick_candidate(parent, cands, o, &is_parent).score.params, 800);
  cands[2].score.val_psnr = 32.0;
  EXPECT_EQ(pick_candidate(parent, cands, o, &is_parent).score.params, 1000);
  EXPECT_TRUE(is_parent);
}

TEST(SearchLoop, ParetoFrontKeepsWhatNothingBeatsOnSizeAndQuality) {
  std::vector<Candidate> cands(5);
  cands[0].score = {32.0, 0, 0, 0, 300, 0, {}, 0};
  cands[1].score = {31.5, 0, 0, 0, 400, 0, {}, 0};  // bigger and worse than [0]
  cands[2].score = {33.0, 0, 0, 0, 800, 0, {}, 0};
  cands[3].score = {32.5, 0, 0, 0, 600, 0, {}, 0};
  cands[4].score = {32.2, 0, 0, 0, 300, 0, {}, 0};  // same size as [0], better
  const auto front = pareto_front(cands);
  ASSERT_EQ(front.size(), 3u);
  EXPECT_EQ(front[0].score.val_psnr, 32.2);
  EXPECT_EQ(front[1].score.params, 600);
  EXPECT_EQ(front[2].score.params, 800);
  EXPECT_TRUE(pareto_front({}).empty());
}

TEST(SearchLoop, EvolutionShrinksTheNetworkAndNeverRetrains) {
  seed_everything(11);
  ScoringEvaluator evaluator(enhanced_pan());
  SearchHistory history(history_path("evolution"), false);
  const auto result = run_search(enhanced_pan(), evaluator, history, small_search());
  EXPECT_FALSE(result.pick_is_parent);
  EXPECT_LT(result.pick.score.params, result.parent.score.params);
  EXPECT_GE(result.pick.score.val_psnr, result.parent.score.val_psnr - 0.05);
  EXPECT_EQ(evaluator.calls(), static_cast<int>(result.evaluated.size()));
  std::set<std::string> keys;
  for (const auto& c : result.evaluated) EXPECT_TRUE(keys.insert(c.key).second) << "trained twice";
}

TEST(SearchLoop, AResumedSearchReachesTheSamePick) {
  seed_everything(5);
  ScoringEvaluator full(enhanced_pan());
  SearchHistory full_history(history_path("full"), false);
  const auto uninterrupted = run_search(enhanced_pan(), full, full_history, small_search());

  const auto path = history_path("killed");
  seed_everything(5);
  ScoringEvaluator killed(enhanced_pan(), /*fail_after=*/7);
  {
    SearchHistory history(path, false);
    EXPECT_THROW(run_search(enhanced_pan(), killed, history, small_search()), Error);
  }
  // A kill may also cut the last line short.
  { std::ofstream(path, std::ios::app) << "{\"generation\": 1, \"key\": \"trunc"; }
  EXPECT_THROW(SearchHistory(path, false), Error);  // never overwritten without --resume
  seed_everything(5);
  ScoringEvaluator resumed(enhanced_pan());
  SearchHistory history(path, true);
  EXPECT_EQ(history.dropped_lines(), 1);
  const auto result = run_search(enhanced_pan(), resumed, history, small_search());
  EXPECT_EQ(result.pick.key, uninterrupted.pick.key);
  EXPECT_EQ(resumed.calls() + 7, full.calls());  // only what was missing was evaluated
}

TEST(SearchLoop, RandomStrategyRunsThroughTheSameLoop) {
  seed_everything(2);
  auto options = small_search();
  options.strategy.type = "random";
  ScoringEvaluator evaluator(enhanced_pan());
  SearchHistory history(history_path("random"), false);
  const auto result = run_search(enhanced_pan(), evaluator, history, options);
  EXPECT_EQ(static_cast<int>(result.evaluated.size()), options.population * options.generations);
}

namespace {
SearchOptions parse_search(const std::string& yaml) {
  return config::parse_document(config::Document::parse(yaml, "search.yaml"), search_schema());
}
std::string search_error(const std::string& yaml) {
  try {
    parse_search(yaml);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}
}  // namespace

TEST(SearchOptions, EachStrategyHasItsOwnOptionsBlockAndABareNameKeepsItsDefaults) {
  const auto block = parse_search("strategy: {type: evolution, mutation_rate: 0.3}\n");
  EXPECT_EQ(block.strategy.type, "evolution");
  EXPECT_DOUBLE_EQ(block.strategy.evolution.mutation_rate, 0.3);
  EXPECT_DOUBLE_EQ(block.strategy.evolution.crossover_rate, EvolutionOptions{}.crossover_rate);
  EXPECT_EQ(parse_search("strategy: random\n").strategy.type, "random");
  // Written back as the block, which reads back the same.
  const std::string emitted = config::to_yaml(search_schema().emit(block));
  EXPECT_NE(emitted.find("type: evolution"), std::string::npos) << emitted;
  EXPECT_DOUBLE_EQ(parse_search(emitted).strategy.evolution.mutation_rate, 0.3);

  EXPECT_NE(search_error("strategy: evolutoin\n").find("did you mean 'evolution'"), std::string::npos);
  EXPECT_NE(search_error("strategy: {mutation_rate: 0.3}\n").find("missing required key 'type'"), std::string::npos);
  EXPECT_NE(search_error("strategy: {type: random, mutation_rate: 0.3}\n")
                .find("search.yaml:1:26: strategy: the random strategy has no options"),
            std::string::npos);
  EXPECT_NE(search_error("strategy: {type: evolution, mutation_rate: 2}\n").find("strategy.mutation_rate"),
            std::string::npos);
}

TEST(SearchOptions, TheFormerSharedOperatorsBlockMovesIntoTheEvolutionBlock) {
  const auto old = parse_search("strategy: evolution\noperators: {mutation_rate: 0.25}\n");
  EXPECT_EQ(old.strategy.type, "evolution");
  EXPECT_DOUBLE_EQ(old.strategy.evolution.mutation_rate, 0.25);
  // The random strategy never read them.
  EXPECT_EQ(parse_search("strategy: random\noperators: {mutation_rate: 0.25}\n").strategy.type, "random");
}

// A candidate's score is written into every history line and distributed reply: the keys, their
// order and null for an unmeasured latency are the format resumed searches read back.
TEST(CandidateScore, JsonKeepsTheHistoryLineFormatAndReadsBack) {
  CandidateScore s{/*val_psnr=*/30.5, /*val_ssim=*/0.875, /*image_loss=*/0.25, /*geometry_loss=*/0,
                   /*params=*/1234,  /*macs=*/56789,     /*latency_ms=*/std::nullopt, /*train_seconds=*/1.5};
  EXPECT_EQ(nlohmann::ordered_json(s).dump(),
            R"({"val_psnr":30.5,"val_ssim":0.875,"image_loss":0.25,"geometry_loss":0.0,"params":1234,"macs":56789,)"
            R"("latency_ms":null,"train_seconds":1.5})");
  s.latency_ms = 2.25;
  const std::string line = nlohmann::ordered_json(s).dump();
  EXPECT_NE(line.find(R"("macs":56789,"latency_ms":2.25,"train_seconds")"), std::string::npos) << line;
  const auto back = nlohmann::json::parse(line).get<CandidateScore>();
  EXPECT_EQ(back.val_psnr, s.val_psnr);
  EXPECT_EQ(back.params, s.params);
  EXPECT_EQ(back.latency_ms, s.latency_ms);
  EXPECT_FALSE(nlohmann::json::parse(R"({"val_psnr":1,"val_ssim":1,"image_loss":0,"geometry_loss":0,"params":1,)"
                                     R"("macs":1,"latency_ms":null,"train_seconds":0})")
                   .get<CandidateScore>()
                   .latency_ms);
  EXPECT_THROW(nlohmann::json::parse(R"({"val_psnr":1})").get<CandidateScore>(), nlohmann::json::exception);
}
