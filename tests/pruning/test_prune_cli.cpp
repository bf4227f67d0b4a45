// `cgsr prune` through the real executable on a tiny rendered scene, after `cgsr search` over an
// elastic network: it writes a valid hybrid model around the search's pick and its results;
// `cgsr eval` then records the per-frame patterns and `cgsr report` tabulates the new rows.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "models/latency_table.h"
#include "pruning/hybrid_model.h"
#include "pruning/pruner.h"
#include "tests/pruning/pruning_cases.h"
#include "tests/support/cli_runner.h"
#include "tests/support/elastic_options.h"

using namespace cgsr;
using namespace cgsr::test;

namespace {
std::string q(const std::filesystem::path& p) { return "'" + p.string() + "'"; }

nlohmann::json results_of(const std::filesystem::path& dir) { return nlohmann::json::parse(slurp(dir / "results.json")); }

// An elastic network as `cgsr train` with elastic.enabled writes it (untrained weights).
void write_elastic_model(const std::filesystem::path& path) {
  torch::manual_seed(18);
  SRNetwork net(small_spec("pan", 2, 3, 8, 8, /*rit=*/true));
  randomize(*net);
  net->eval();
  const ElasticNetwork elastic = make_elastic(*net, test::elastic_options(2, 0.25, 1));
  LatencyTableOptions latency;
  latency.runs = 1;
  latency.calibration_subnets = 2;
  latency.check_subnets = 1;
  latency.subnet_runs = 1;
  Provenance p;
  p.stage = "elastic";
  p.extra = {{"name", "tiny elastic"},
             {"elastic", elastic_metadata(elastic.space)},
             {"latency_table", to_json(measure_latency_table(*elastic.network, elastic.space, 64, 48, latency))}};
  save_model(path, *elastic.network, p);
}
}  // namespace

TEST(PruneCli, PrunesAroundASearchPickEndToEnd) {
  const auto dir = scratch_dir("prune-cli");
  const std::string source = CGSR_SOURCE_DIR;
  auto r = run_cgsr("render --config '" + source + "/configs/scenes/tiny.yaml' --out " + q(dir / "data"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  write_elastic_model(dir / "elastic.cgsr");
  r = run_cgsr("search --model " + q(dir / "elastic.cgsr") + " --data " + q(dir / "data") +
               " --set population=6 --set generations=2 --set name=tiny --set pick.latency_fraction=0.5" +
               " --set pick.measure_runs=0" +  // the table's pick: timings at 64x48 are noise
               " --set crops.frames=1 --set crops.size=16 --set final.schedule.steps=2" +
               " --set final.schedule.batch_size=2 --set final.schedule.patch_size=16 --set final.schedule.val_frames=1" +
               " --out " + q(dir / "search"));
  ASSERT_EQ(r.exit_code, 0) << r.err;

  const std::string common = "prune --config '" + source + "/configs/prune/quick.yaml' --model " +
                             q(dir / "elastic.cgsr") + " --search " + q(dir / "search" / "results.json") +
                             " --data " + q(dir / "data") +
                             " --set finetune.schedule.steps=3 --set selector.steps=5 --set eval.latency_runs=1";
  r = run_cgsr(common + " --out " + q(dir / "run"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const HybridModel h = load_hybrid_model(dir / "run" / "pruned.cgsr");
  EXPECT_EQ(h.samplers->patterns(), std::vector<int>{h.pool.size()});
  EXPECT_EQ(h.latency.median_ms.size(), static_cast<size_t>(h.pool.size()));
  const auto results = results_of(dir / "run");
  ASSERT_EQ(results["evaluations"].size(), 3u);
  EXPECT_EQ(results["evaluations"][0]["name"], "tiny");
  EXPECT_EQ(results["evaluations"][1]["name"], "tiny static");
  EXPECT_EQ(results["evaluations"][2]["name"], "tiny hybrid");
  EXPECT_TRUE(results["left_out"].contains("channels"));
  EXPECT_TRUE(results["finetune"]["steps"].get<int>() == 3);
  // The quick config's three patterns (or fewer, when the front is shorter), priced by the table.
  const auto& cost = results["selector"]["cost"];
  ASSERT_GE(cost.size(), 1u);
  EXPECT_LE(cost.size(), 3u);
  EXPECT_DOUBLE_EQ(cost[0].get<double>(), 1.0);
  for (size_t k = 1; k < cost.size(); ++k) EXPECT_LT(cost[k].get<double>(), cost[k - 1].get<double>());
  EXPECT_EQ(results["selector"]["frames"].size(), results["selector"]["best"].size());
  // Every evaluated model has its role and file.
  const PruneRoles roles = prune_roles_from_json(results["roles"], "results.json");
  EXPECT_EQ(roles.input.name, "tiny");
  EXPECT_EQ(roles.input.file, dir / "search" / "model.cgsr");
  EXPECT_EQ(roles.hybrid.name, "tiny hybrid");
  EXPECT_EQ(roles.static_network.name, "tiny static");
  const auto frame = results["evaluations"][2]["frames"][0];
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

  // A search results file that is not one, and a missing model, are errors naming the file.
  std::ofstream(dir / "not_search.json") << "{\"x\": 1}";
  r = run_cgsr("prune --config '" + source + "/configs/prune/quick.yaml' --model " + q(dir / "elastic.cgsr") +
               " --search " + q(dir / "not_search.json") + " --data " + q(dir / "data") + " --out " + q(dir / "bad"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("not_search.json"), std::string::npos) << r.err;
  r = run_cgsr("prune --config '" + source + "/configs/prune/quick.yaml' --model " + q(dir / "missing.cgsr") +
               " --search " + q(dir / "search" / "results.json") + " --data " + q(dir / "data") + " --out " +
               q(dir / "bad2"));
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
  const nlohmann::ordered_json j = roles;
  EXPECT_EQ(j.dump(), R"({"input":{"name":"cg-optimized","file":"in/model.cgsr"},)"
                      R"("hybrid":{"name":"hybrid","file":"out/pruned.cgsr"},)"
                      R"("static_network":{"name":"static","file":"out/pruned.cgsr"}})");
  const PruneRoles back = prune_roles_from_json(j, "results.json");
  EXPECT_EQ(back.static_network.file, roles.static_network.file);
  EXPECT_EQ(back.input.name, "cg-optimized");
  auto broken = j;
  broken["hybrid"].erase("file");
  EXPECT_THROW(prune_roles_from_json(broken, "results.json"), Error);
}
