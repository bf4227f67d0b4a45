// The verdict of `cgsr run`: each claim passes or fails on the figures it is given, and a missing
// measurement is a failed check, never a silent pass.
#include <gtest/gtest.h>

#include "pipeline/verdict.h"

using namespace cgsr;

namespace {
EvalResult result(const std::string& name, double psnr, int64_t params, int64_t macs, double latency_ms,
                  double psnr_edge = 20.0) {
  EvalResult r;
  r.name = name;
  r.psnr = psnr;
  r.psnr_edge = psnr_edge;
  if (params > 0) {
    Complexity c;
    c.params = params;
    c.macs = macs;
    r.cost = c;
  }
  if (latency_ms > 0) {
    LatencyStats l;
    l.median_ms = latency_ms;
    l.runs = 5;
    r.latency = l;
  }
  return r;
}

const VerdictCheck* find(const Verdict& v, const std::string& claim) {
  for (const auto& c : v.checks)
    if (c.claim == claim) return &c;
  return nullptr;
}

struct Story {
  EvalResult bicubic = result("bicubic", 24.0, 0, 0, 2.0);
  EvalResult pan = result("PAN", 26.0, 272000, 20000000, 100.0);
  EvalResult control = result("PAN on", 26.05, 272000, 20000000, 100.0, 20.0);
  EvalResult cg = result("CG", 26.2, 280000, 21000000, 110.0, 20.5);
  EvalResult opt = result("OPT", 26.1, 150000, 11000000, 60.0);
  EvalResult pruned = result("P", 26.0, 60000, 4000000, 30.0);
  PipelineResults roles() const {
    PipelineResults r;
    r.bicubic = &bicubic;
    r.backbone = &pan;
    r.control = &control;
    r.cg_enhanced = &cg;
    r.cg_optimized = &opt;
    r.pruned = &pruned;
    return r;
  }
};
}  // namespace

TEST(PipelineVerdict, TheExpectedStoryPassesEveryCheck) {
  const Story s;
  const Verdict v = judge_pipeline(s.roles(), VerdictOptions{});
  // 5 networks above bicubic, CG's gain over the control overall and on edges, and 4 checks
  // each for search and pruning.
  EXPECT_EQ(v.checks.size(), 5u + 2u + 4u + 4u);
  EXPECT_TRUE(v.passed()) << v.text();
  EXPECT_NE(v.text().find("all 15 checks pass"), std::string::npos);
  EXPECT_EQ(v.to_json()["passed"], true);
  const auto first = v.to_json()["checks"][0];
  EXPECT_EQ(first.dump(), nlohmann::ordered_json({{"claim", v.checks[0].claim}, {"passed", true}, {"detail", v.checks[0].detail}}).dump());
  EXPECT_EQ(Verdict{}.to_json().dump(), R"({"passed":true,"checks":[]})");
}

TEST(PipelineVerdict, EachClaimFailsOnItsOwn) {
  {
    Story s;
    s.pruned.psnr = 23.9;  // below bicubic, and a 2.2 dB loss
    const Verdict v = judge_pipeline(s.roles(), VerdictOptions{});
    EXPECT_FALSE(find(v, "P beats bicubic")->passed);
    EXPECT_FALSE(find(v, "pruning loses at most 0.3 dB")->passed);
    EXPECT_EQ(v.failed(), 2) << v.text();
  }
  {
    Story s;
    s.cg.psnr = 26.04;  // above its shorter-trained parent, below the control trained as long
    const Verdict v = judge_pipeline(s.roles(), VerdictOptions{});
    EXPECT_FALSE(find(v, "CG gains at least 0 dB overall over PAN on")->passed);
    EXPECT_TRUE(find(v, "CG gains at least 0 dB on geometry edges over PAN on")->passed);
    EXPECT_EQ(v.failed(), 1) << v.text();
  }
  {
    Story s;  // CG gains 0.15 dB overall and 0.5 dB on edges
    VerdictOptions o;
    o.min_enhance_gain_db = 0.2;
    o.min_enhance_edge_gain_db = 0.5;
    const Verdict v = judge_pipeline(s.roles(), o);
    EXPECT_FALSE(find(v, "CG gains at least 0.2 dB overall over PAN on")->passed);
    EXPECT_TRUE(find(v, "CG gains at least 0.5 dB on geometry edges over PAN on")->passed);
    s.cg.psnr_edge = 20.49;
    EXPECT_FALSE(find(judge_pipeline(s.roles(), o), "CG gains at least 0.5 dB on geometry edges over PAN on")->passed);
  }
  {
    Story s;
    s.opt.latency->median_ms = 110.0;  // equal is not a cut
    const Verdict v = judge_pipeline(s.roles(), VerdictOptions{});
    EXPECT_FALSE(find(v, "search cuts latency")->passed);
    EXPECT_TRUE(find(v, "search cuts params")->passed);
    EXPECT_EQ(v.failed(), 1);
  }
  {
    Story s;
    s.opt.psnr = 25.85;  // 0.35 dB below its parent: over 0.3, within 0.4
    VerdictOptions o;
    EXPECT_FALSE(judge_pipeline(s.roles(), o).passed());
    o.max_search_loss_db = 0.4;
    EXPECT_TRUE(judge_pipeline(s.roles(), o).passed());
  }
}

TEST(PipelineVerdict, MissingMeasurementsFail) {
  Story s;
  s.pruned.latency.reset();
  s.pruned.cost.reset();
  const Verdict v = judge_pipeline(s.roles(), VerdictOptions{});
  EXPECT_FALSE(find(v, "pruning cuts latency")->passed);
  EXPECT_FALSE(find(v, "pruning cuts params and MACs")->passed);
  EXPECT_NE(v.text().find("FAILED"), std::string::npos);
}

namespace {
// A hybrid that chose `patterns[i]` on frame i, with mean and p95 latency per frame.
EvalResult hybrid(double psnr, double mean_ms, const std::vector<int>& patterns) {
  EvalResult r = result("H", psnr, 60000, 3000000, mean_ms);
  r.latency->mean_ms = mean_ms;
  r.latency->p95_ms = mean_ms * 1.5;
  for (size_t i = 0; i < patterns.size(); ++i) {
    FrameScore f;
    f.frame = static_cast<int>(i);
    f.choice = PatternChoice{patterns[i], 1.0 - 0.2 * patterns[i]};
    r.frames.push_back(f);
  }
  return r;
}
}  // namespace

TEST(PipelineVerdict, TheDynamicPartMustPayAgainstItsStaticNetworkAndMagnitudePruning) {
  Story s;
  EvalResult fixed = result("P static", 26.02, 60000, 4000000, 30.0);
  fixed.latency->mean_ms = 30.0;
  EvalResult mmp = result("P MMP", 25.9, 45000, 3000000, 24.0);
  const auto judge = [&](const EvalResult& h, const VerdictOptions& o = VerdictOptions{}) {
    PipelineResults r = s.roles();
    r.pruned = &h;
    r.pruned_static = &fixed;
    r.magnitude = &mmp;
    return judge_pipeline(r, o);
  };
  // 22 ms against 30 ms (0.73x), 0.02 dB below the static network, +0.1 dB over MMP, 3 patterns.
  const EvalResult good = hybrid(26.0, 22.0, {0, 1, 2, 2, 1});
  const Verdict v = judge(good);
  EXPECT_TRUE(v.passed()) << v.text();
  EXPECT_EQ(v.checks.size(), 15u + 4u);
  EXPECT_NE(find(v, "H uses at least 3 patterns on the test frames")->detail.find("pattern 2: 2 frames (40%)"),
            std::string::npos);

  EXPECT_FALSE(find(judge(hybrid(26.0, 25.0, {0, 1, 2})), "H runs at most 0.8x its static network's mean latency")
                   ->passed);
  EXPECT_FALSE(find(judge(hybrid(25.95, 22.0, {0, 1, 2})), "H loses at most 0.05 dB against its static network")->passed);
  EXPECT_FALSE(find(judge(hybrid(25.93, 22.0, {0, 1, 2})), "H gains at least 0.05 dB over P MMP")->passed);
  EXPECT_FALSE(find(judge(hybrid(26.0, 22.0, {0, 2, 2})), "H uses at least 3 patterns on the test frames")->passed);
  VerdictOptions two;
  two.min_patterns_used = 2;
  EXPECT_TRUE(find(judge(hybrid(26.0, 22.0, {0, 2, 2}), two), "H uses at least 2 patterns on the test frames")->passed);

  // Without latency the claim fails rather than passing silently.
  EvalResult untimed = good;
  untimed.latency.reset();
  EXPECT_FALSE(find(judge(untimed), "H runs at most 0.8x its static network's mean latency")->passed);
}

TEST(PipelineVerdict, EveryNetworkMustBeatBicubicOnEveryHeldOutScene) {
  const Story s;
  // On the held-out scene bicubic does better than in the run's own scene: PAN loses to it.
  const EvalResult bicubic = result("bicubic", 35.3, 0, 0, 0);
  const EvalResult pan = result("PAN", 35.1, 272000, 20000000, 0);
  const EvalResult cg = result("CG", 35.5, 280000, 21000000, 0);
  PipelineResults r = s.roles();
  r.heldout.push_back({"level", &bicubic, {&pan, &cg}});
  const Verdict v = judge_pipeline(r, VerdictOptions{});
  EXPECT_EQ(v.checks.size(), 15u + 2u);
  EXPECT_FALSE(find(v, "PAN beats bicubic on held-out scene 'level'")->passed);
  EXPECT_NE(find(v, "PAN beats bicubic on held-out scene 'level'")->detail.find("-0.200 dB"), std::string::npos);
  EXPECT_TRUE(find(v, "CG beats bicubic on held-out scene 'level'")->passed);
  EXPECT_EQ(v.failed(), 1) << v.text();

  // A held-out scene without its bicubic row is a failed check, not a silent pass.
  PipelineResults missing = s.roles();
  missing.heldout.push_back({"level", nullptr, {&pan}});
  EXPECT_FALSE(find(judge_pipeline(missing, VerdictOptions{}), "bicubic evaluated on held-out scene 'level'")->passed);
}
