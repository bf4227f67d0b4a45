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
  EvalResult elastic = result("E", 26.18, 280000, 21000000, 110.0);
  EvalResult opt = result("OPT", 26.0, 90000, 7000000, 30.0);
  EvalResult scratch = result("OPT scratch", 25.85, 90000, 7000000, 30.0);
  EvalResult mmp = result("CG MMP", 25.9, 150000, 8000000, 29.0);
  EvalResult uniform = result("CG uniform", 25.8, 100000, 7000000, 35.0);
  PipelineResults roles() const {
    PipelineResults r;
    r.bicubic = &bicubic;
    r.backbone = &pan;
    r.control = &control;
    r.cg_enhanced = &cg;
    r.elastic = &elastic;
    r.cg_optimized = &opt;
    r.scratch = &scratch;
    r.controls = {&mmp, &uniform};
    r.magnitude = &mmp;
    r.searches = {{"evolution", 1000, 5.0}, {"random", 1000, 4.0}};
    return r;
  }
};

// 5 networks above bicubic, CG's gain over the control overall and on edges, the elastic loss,
// 4 search cuts, the search's evaluations and hypervolume, and the final network against the
// backbone (latency, PSNR), its scratch twin and both controls.
constexpr size_t kStoryChecks = 5 + 2 + 1 + 4 + 2 + 5;
}  // namespace

TEST(PipelineVerdict, TheExpectedStoryPassesEveryCheck) {
  const Story s;
  const Verdict v = judge_pipeline(s.roles(), VerdictOptions{});
  EXPECT_EQ(v.checks.size(), kStoryChecks) << v.text();
  EXPECT_TRUE(v.passed()) << v.text();
  EXPECT_NE(v.text().find("all 19 checks pass"), std::string::npos);
  EXPECT_EQ(v.to_json()["passed"], true);
  const auto first = v.to_json()["checks"][0];
  EXPECT_EQ(first.dump(), nlohmann::ordered_json({{"claim", v.checks[0].claim}, {"passed", true}, {"detail", v.checks[0].detail}}).dump());
  EXPECT_EQ(Verdict{}.to_json().dump(), R"({"passed":true,"checks":[]})");
  // The uniform control is slower than the final network: it is no threat, and says so.
  EXPECT_NE(find(v, "OPT beats CG uniform by 0.05 dB when that is as fast")->detail.find("slower"), std::string::npos);
}

TEST(PipelineVerdict, EachClaimFailsOnItsOwn) {
  const auto failed = [](const Verdict& v) {
    std::vector<std::string> out;
    for (const auto& c : v.checks)
      if (!c.passed) out.push_back(c.claim);
    return out;
  };
  {
    Story s;
    s.cg.psnr = 26.04;  // above its shorter-trained parent, below the control trained as long
    const Verdict v = judge_pipeline(s.roles(), VerdictOptions{});
    EXPECT_EQ(failed(v), (std::vector<std::string>{"CG gains at least 0 dB overall over PAN on"})) << v.text();
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
    s.elastic.psnr = 26.1;  // 0.1 dB below the network it was trained from
    EXPECT_EQ(failed(judge_pipeline(s.roles(), VerdictOptions{})),
              (std::vector<std::string>{"E loses at most 0.05 dB against CG"}));
  }
  {
    Story s;
    s.opt.latency->median_ms = 36.0;  // 36% of PAN's; the uniform control is now as fast
    EXPECT_EQ(failed(judge_pipeline(s.roles(), VerdictOptions{})),
              (std::vector<std::string>{"OPT runs at most 0.35 of PAN's latency"}));
  }
  {
    Story s;
    s.scratch.psnr = 25.95;  // trained from scratch as long, only 0.05 dB below
    EXPECT_EQ(failed(judge_pipeline(s.roles(), VerdictOptions{})),
              (std::vector<std::string>{"OPT gains at least 0.1 dB overall over OPT scratch"}));
  }
  {
    Story s;
    s.mmp.psnr = 25.97;  // as fast and within 0.05 dB
    EXPECT_EQ(failed(judge_pipeline(s.roles(), VerdictOptions{})),
              (std::vector<std::string>{"OPT beats CG MMP by 0.05 dB when that is as fast"}));
  }
  {
    Story s;
    PipelineResults r = s.roles();
    r.searches = {{"evolution", 900, 4.0}, {"random", 900, 4.5}};
    EXPECT_EQ(failed(judge_pipeline(r, VerdictOptions{})),
              (std::vector<std::string>{"the search scores at least 1000 subnets",
                                        "evolution's front dominates random's at as many evaluations (hypervolume)"}));
  }
  {
    Story s;
    s.opt.psnr = 25.85;  // 0.35 dB below its parent: over 0.3, within 0.4
    VerdictOptions o;
    EXPECT_FALSE(find(judge_pipeline(s.roles(), o), "search loses at most 0.3 dB")->passed);
    o.max_search_loss_db = 0.4;
    EXPECT_TRUE(find(judge_pipeline(s.roles(), o), "search loses at most 0.4 dB")->passed);
  }
}

TEST(PipelineVerdict, MissingMeasurementsFail) {
  Story s;
  s.opt.latency.reset();
  s.opt.cost.reset();
  const Verdict v = judge_pipeline(s.roles(), VerdictOptions{});
  EXPECT_FALSE(find(v, "search cuts latency")->passed);
  EXPECT_FALSE(find(v, "search cuts params and MACs")->passed);
  EXPECT_FALSE(find(v, "OPT runs at most 0.35 of PAN's latency")->passed);
  EXPECT_FALSE(find(v, "OPT beats CG MMP by 0.05 dB when that is as fast")->passed);
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

TEST(PipelineVerdict, TheDynamicPartMustPayAgainstItsStaticNetworkThePickAndMagnitudePruning) {
  Story s;
  s.mmp.latency->mean_ms = 29.0;
  s.opt.latency->mean_ms = 30.0;
  EvalResult fixed = result("P static", 26.02, 60000, 4000000, 40.0);
  fixed.latency->mean_ms = 30.0;
  const auto judge = [&](const EvalResult& h, const VerdictOptions& o = VerdictOptions{}) {
    PipelineResults r = s.roles();
    r.pruned = &h;
    r.pruned_static = &fixed;
    return judge_pipeline(r, o);
  };
  // 22 ms against 30 ms (0.73x), 0.02 dB below the static network, as good as the pick, +0.1 dB
  // over MMP, 3 patterns; and above bicubic.
  const EvalResult good = hybrid(26.0, 22.0, {0, 1, 2, 2, 1});
  const Verdict v = judge(good);
  EXPECT_TRUE(v.passed()) << v.text();
  EXPECT_EQ(v.checks.size(), kStoryChecks + 6);
  EXPECT_NE(find(v, "H uses at least 3 patterns on the test frames")->detail.find("pattern 2: 2 frames (40%)"),
            std::string::npos);

  EXPECT_FALSE(find(judge(hybrid(26.0, 25.0, {0, 1, 2})), "H runs at most 0.8x its static network's mean latency")
                   ->passed);
  EXPECT_FALSE(find(judge(hybrid(25.95, 22.0, {0, 1, 2})), "H loses at most 0.05 dB against its static network")->passed);
  EXPECT_FALSE(find(judge(hybrid(25.93, 22.0, {0, 1, 2})), "H gains at least 0.05 dB over CG MMP")->passed);
  EXPECT_FALSE(find(judge(hybrid(25.99, 22.0, {0, 1, 2})), "H gains at least 0 dB over OPT")->passed);
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
  EXPECT_EQ(v.checks.size(), kStoryChecks + 2);
  EXPECT_FALSE(find(v, "PAN beats bicubic on held-out scene 'level'")->passed);
  EXPECT_NE(find(v, "PAN beats bicubic on held-out scene 'level'")->detail.find("-0.200 dB"), std::string::npos);
  EXPECT_TRUE(find(v, "CG beats bicubic on held-out scene 'level'")->passed);
  EXPECT_EQ(v.failed(), 1) << v.text();

  // On a held-out scene with the final network and its scratch twin, the gain is checked there too.
  const EvalResult opt = result("OPT", 35.6, 90000, 7000000, 0), scratch = result("OPT scratch", 35.55, 90000, 7000000, 0);
  PipelineResults with_scratch = s.roles();
  with_scratch.heldout.push_back({"level", &bicubic, {&opt}, &opt, &scratch});
  EXPECT_FALSE(find(judge_pipeline(with_scratch, VerdictOptions{}),
                    "OPT gains at least 0.1 dB on held-out scene 'level' over OPT scratch")
                   ->passed);

  // A held-out scene without its bicubic row is a failed check, not a silent pass.
  PipelineResults missing = s.roles();
  missing.heldout.push_back({"level", nullptr, {&pan}});
  EXPECT_FALSE(find(judge_pipeline(missing, VerdictOptions{}), "bicubic evaluated on held-out scene 'level'")->passed);
}
