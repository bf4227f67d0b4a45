// `cgsr prune` through the real executable on a tiny rendered scene: it writes a valid hybrid
// model, the baseline and results; `cgsr eval` then records the per-frame patterns and
// `cgsr report` tabulates the new rows.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "pruning/hybrid_model.h"
#include "pruning/pruner.h"
#include "tests/pruning/pruning_cases.h"
#include "tests/support/cli_runner.h"

using namespace cgsr;
using namespace cgsr::test;

namespace {
std::string q(const std::filesystem::path& p) { return "'" + p.string() + "'"; }

nlohmann::json results_of(const std::filesystem::path& dir) { return nlohmann::json::parse(slurp(dir / "results.json")); }
}  // namespace

TEST(PruneCli, PrunesATinySceneEndToEnd) {
  const auto dir = scratch_dir("prune-cli");
  const std::string source = CGSR_SOURCE_DIR;
  auto r = run_cgsr("render --config '" + source + "/configs/scenes/tiny.yaml' --out " + q(dir / "data"));
  ASSERT_EQ(r.exit_code, 0) << r.err;

  torch::manual_seed(18);
  SRNetwork net(small_spec("pan", 2, 2, 6, 8, /*rit=*/true));
  randomize(*net);
  Provenance p;
  p.extra = {{"name", "tiny"}};
  save_model(dir / "model.cgsr", *net, p);

  const std::string common = "prune --config '" + source + "/configs/prune/quick.yaml' --model " +
                             q(dir / "model.cgsr") + " --data " + q(dir / "data") +
                             " --set finetune.schedule.steps=3 --set selector.steps=5 --set eval.latency_runs=1";
  r = run_cgsr(common + " --set 'baselines=[{type: magnitude}, {type: taylor, keep_rate: 0.5}]' --out " +
               q(dir / "run"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const HybridModel h = load_hybrid_model(dir / "run" / "pruned.cgsr");
  EXPECT_EQ(h.samplers->patterns(), std::vector<int>{h.pool.size()});
  EXPECT_EQ(h.latency.median_ms.size(), static_cast<size_t>(h.pool.size()));
  EXPECT_TRUE(std::filesystem::exists(dir / "run" / "baseline0_magnitude.cgsr"));
  const auto results = results_of(dir / "run");
  ASSERT_EQ(results["evaluations"].size(), 5u);
  EXPECT_EQ(results["evaluations"][0]["name"], "tiny");
  EXPECT_EQ(results["evaluations"][1]["name"], "tiny MMP");
  EXPECT_EQ(results["evaluations"][2]["name"], "tiny taylor pruning 0.50");
  EXPECT_EQ(results["evaluations"][3]["name"], "tiny static");
  EXPECT_EQ(results["evaluations"][4]["name"], "tiny hybrid");
  EXPECT_TRUE(results["left_out"].contains("channels"));
  EXPECT_TRUE(results["left_out"]["geometry_head"].is_boolean());
  EXPECT_LE(results["comparison"][4]["macs_ratio"].get<double>(), 1.0);
  // The quick config's three patterns, each measured on the 16 selector frames.
  EXPECT_EQ(results["selector"]["cost"].size(), 3u);
  EXPECT_EQ(results["selector"]["frames"].size(), results["selector"]["best"].size());
  EXPECT_DOUBLE_EQ(results["selector"]["cost"][0].get<double>(), 1.0);
  EXPECT_LT(results["selector"]["cost"][2].get<double>(), results["selector"]["cost"][1].get<double>());
  // Every evaluated model has its role and file.
  const PruneRoles roles = prune_roles_from_json(results["roles"], "results.json");
  EXPECT_EQ(roles.input.name, "tiny");
  EXPECT_EQ(roles.hybrid.name, "tiny hybrid");
  EXPECT_EQ(roles.static_network.name, "tiny static");
  ASSERT_EQ(roles.baselines.size(), 2u);
  EXPECT_EQ(roles.baselines[0].name, "tiny MMP");
  EXPECT_DOUBLE_EQ(roles.baselines[1].keep_rate, 0.5);
  EXPECT_EQ(roles.baselines[1].file, dir / "run" / "baseline1_taylor.cgsr");
  EXPECT_EQ(roles.baselines[0].file, dir / "run" / "baseline0_magnitude.cgsr");
  EXPECT_GT(roles.baselines[0].keep_rate, 0.0);
  EXPECT_LE(roles.baselines[0].keep_rate, 1.0);
  EXPECT_EQ(roles.baseline("magnitude"), &roles.baselines[0]);
  EXPECT_EQ(roles.baseline("taylor"), &roles.baselines[1]);
  EXPECT_EQ(roles.baseline("activation"), nullptr);
  const auto frame = results["evaluations"][4]["frames"][0];
  EXPECT_TRUE(frame["details"]["pattern"].is_number_integer());
  EXPECT_GE(frame["details"]["choose_ms"].get<double>(), 0.0);

  r = run_cgsr("eval --data " + q(dir / "data") + " --model " + q(dir / "run" / "pruned.cgsr") + " --out " +
               q(dir / "eval"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto eval = results_of(dir / "eval");
  EXPECT_EQ(eval["evaluations"][0]["name"], "tiny hybrid");
  EXPECT_TRUE(eval["evaluations"][0]["frames"][0]["details"]["pattern"].is_number_integer());

  r = run_cgsr("report " + q(dir / "run") + " --out " + q(dir / "report"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string report = slurp(dir / "report" / "report.md");
  EXPECT_NE(report.find("tiny hybrid"), std::string::npos);
  // The hybrid's choice per frame, next to each frame's edge density, as a table and a plot.
  EXPECT_NE(report.find("#### tiny hybrid: the pattern chosen per frame"), std::string::npos) << report;
  EXPECT_TRUE(std::filesystem::exists(dir / "report" / "pattern_choice_tiny_x2_5.png"));

  r = run_cgsr("prune --config '" + source + "/configs/prune/quick.yaml' --model " + q(dir / "missing.cgsr") +
               " --data " + q(dir / "data") + " --out " + q(dir / "bad"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("missing.cgsr"), std::string::npos) << r.err;
  std::filesystem::remove_all(dir);
}

// The roles block of a prune stage's results.json, which `cgsr run` reads back on a rerun.
TEST(PruneRoles, JsonKeepsItsFormatAndReadsBack) {
  PruneRoles roles;
  roles.input = {"cg-optimized", "in/model.cgsr"};
  roles.hybrid = {"hybrid", "out/pruned.cgsr"};
  roles.static_network = {"static", "out/pruned.cgsr"};
  PrunedBaseline mmp;
  mmp.name = "mmp";
  mmp.file = "out/mmp.cgsr";
  mmp.options.type = "magnitude";
  mmp.options.keep_rate = 0;
  mmp.keep_rate = 0.5;
  roles.baselines.push_back(mmp);
  const auto j = to_json(roles);
  EXPECT_EQ(j.dump(), R"({"input":{"name":"cg-optimized","file":"in/model.cgsr"},)"
                      R"("hybrid":{"name":"hybrid","file":"out/pruned.cgsr"},)"
                      R"("static":{"name":"static","file":"out/pruned.cgsr"},)"
                      R"("baselines":[{"name":"mmp","file":"out/mmp.cgsr","type":"magnitude",)"
                      R"("requested_keep_rate":0.0,"keep_rate":0.5}]})");
  const PruneRoles back = prune_roles_from_json(j, "results.json");
  EXPECT_EQ(back.static_network.file, roles.static_network.file);
  ASSERT_EQ(back.baselines.size(), 1u);
  EXPECT_EQ(back.baselines[0].name, "mmp");
  EXPECT_EQ(back.baselines[0].file, "out/mmp.cgsr");
  EXPECT_EQ(back.baselines[0].keep_rate, 0.5);
  auto broken = j;
  broken["hybrid"].erase("file");
  EXPECT_THROW(prune_roles_from_json(broken, "results.json"), Error);
}
