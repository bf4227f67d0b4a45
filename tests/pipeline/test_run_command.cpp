// `cgsr run` end to end on the tiny scene with tiny schedules: every stage leaves its artifacts
// and a finished-stage record, a rerun skips everything, `--from` and a changed stage config
// rerun exactly the stages they should, a held-out scene gets its section and verdict checks, and
// a stage's config error names the run config's key.
// The CG-enhanced network reads HR rendering information through both HR sources, so search,
// pruning, export and the report all handle the second input.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "tests/support/cli_runner.h"
#include "tests/support/page_links.h"

using namespace cgsr::test;
namespace fs = std::filesystem;

namespace {

const char* kConfig = R"(name: tiny-pipeline
scene: SCENE
baselines: [bicubic, nearest]
train:
  model: pan
  name: PAN x2
  schedule: {steps: 6, batch_size: 2, patch_size: 16, validate_every: 0, val_frames: 1, checkpoint_every: 3}
enhance:
  name: CG-enhanced PAN x2
  rit: {channels: [depth, normal_angle, edge], width: 8, hr_width: 8, source: hr_unshuffle+hr_fuse}
  geometry: {enabled: true, width: 8}
  schedule: {steps: 4, batch_size: 2, patch_size: 16, validate_every: 0, val_frames: 1}
elastic:
  space: {quantum: 4, min_width_fraction: 0.5, min_blocks: 2}
  sampled: 1
  schedule: {steps: 4, batch_size: 2, patch_size: 16, validate_every: 0, val_frames: 1}
  latency: {runs: 1, calibration_subnets: 2, check_subnets: 1, subnet_runs: 1}
search:
  name: CG-optimized PAN x2
  population: 4
  generations: 2
  crops: {frames: 1, crops_per_frame: 2, size: 12, margin: 2}
  pick: {latency_fraction: 0.6}
  final:
    schedule: {steps: 2, batch_size: 2, patch_size: 16, validate_every: 0, val_frames: 1}
scratch: {steps: 3}
prune:
  pool: {latency_factors: [1.2, 1.0, 0.8]}
  sampler: {grid: 4, width: 2}
  selector: {steps: 2, latency_runs: 1}
  finetune:
    schedule: {steps: 2, batch_size: 2, patch_size: 16, validate_every: 0, val_frames: 1}
eval: {max_frames: 2, latency_runs: 1}
heldout: {scenes: [HELDOUT], frames: 2}
verdict: {fail_run: false, min_search_evaluations: 8}
)";

// A scene the networks never train on: another room of the tiny scene's kind.
const char* kHeldoutScene = R"(name: tiny-heldout
frames: 6
resolutions: [32x24, 64x48]
shadows: false
scene:
  type: procedural
  name: tiny-heldout
  layout: room
  size: [7, 6]
  cell: 2.0
  texture_size: 32
  texel_density: 40
  props: {crates: 2, pillars: 0, spheres: 2, tori: 0, stairs: 0, fences: 0, railings: 1, wires: 2, signs: 1}
  lighting: {point_lights: 2, shadows: false}
  camera: {steps: 4}
)";

// The pipeline config above, on the tiny scene with the held-out scene, written into `dir`.
fs::path write_config(const fs::path& dir) {
  std::string config = kConfig;
  config.replace(config.find("SCENE"), 5, std::string(CGSR_SOURCE_DIR) + "/configs/scenes/tiny.yaml");
  std::ofstream(dir / "heldout.yaml") << kHeldoutScene;
  config.replace(config.find("HELDOUT"), 7, (dir / "heldout.yaml").string());
  const auto file = dir / "pipeline.yaml";
  std::ofstream(file) << config;
  return file;
}

// Stage name -> "ran" / "skipped", from the log lines of one cgsr run.
std::map<std::string, std::string> stage_actions(const std::string& log) {
  std::map<std::string, std::string> out;
  for (const std::string stage :
       {"render", "train", "enhance", "control", "elastic", "search", "prune", "scratch", "controls", "export", "eval",
        "heldout", "report"}) {
    if (log.find("] " + stage + ": up to date") != std::string::npos)
      out[stage] = "skipped";
    else if (log.find("] " + stage + ": done in") != std::string::npos)
      out[stage] = "ran";
  }
  return out;
}

void expect_actions(const CliResult& r, const std::map<std::string, std::string>& expected) {
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto actions = stage_actions(r.err);
  for (const auto& [stage, action] : expected) {
    ASSERT_TRUE(actions.count(stage)) << stage << "\n" << r.err;
    EXPECT_EQ(actions.at(stage), action) << stage;
  }
}

}  // namespace

TEST(RunCommand, RunsEveryStageThenCachesThem) {
  const auto dir = scratch_dir("run-command");
  const auto config_file = write_config(dir);
  const auto out = dir / "run";
  const std::string args = "run --config " + config_file.string() + " --out " + out.string() + " --threads 2 --seed 3";

  const CliResult first = run_cgsr(args);
  ASSERT_EQ(first.exit_code, 0) << first.err;
  for (const auto& [stage, action] : stage_actions(first.err)) EXPECT_EQ(action, "ran") << stage;
  EXPECT_EQ(stage_actions(first.err).size(), 13u) << first.err;
  for (const std::string stage : {"data", "train", "enhance", "control", "elastic", "search", "prune", "scratch",
                                  "controls", "export", "eval", "heldout", "report"})
    EXPECT_TRUE(read_json(out / stage / "stage.json")["done"].get<bool>()) << stage;
  for (const std::string file : {"train/model.cgsr", "enhance/model.cgsr", "control/model.cgsr", "elastic/model.cgsr",
                                 "search/model.cgsr", "search/history.jsonl", "search/random_history.jsonl",
                                 "search/front.png", "scratch/model.cgsr", "controls/magnitude.cgsr",
                                 "controls/uniform.cgsr", "prune/pruned.cgsr",
                                 "export/cg_optimized.onnx", "export/pruned/pattern_0.onnx", "export/pruned/selector.onnx",
                                 "export/pruned/manifest.json", "export/pruned_torchscript/pattern_0.pt",
                                 "heldout/1_heldout/data/manifest.yaml", "heldout/1_heldout/eval/results.json",
                                 "report/report.md", "verdict.txt", "results.json", "log.txt"})
    EXPECT_TRUE(fs::exists(out / file)) << file;
  // The pick is timed against the backbone, what the verdict's latency check divides by; the
  // controls against the pick, each cut kept for a resumed run.
  EXPECT_EQ(read_json(out / "search" / "pick.json")["reference"], "PAN x2");
  for (const std::string kind : {"magnitude", "uniform"})
    EXPECT_GT(read_json(out / "controls" / ("cut_" + kind + ".json"))["latency_fraction"].get<double>(), 0) << kind;

  // The report holds every model of the pipeline; the verdict judges them.
  const std::string report = slurp(out / "report" / "report.md");
  for (const std::string row : {"bicubic", "nearest", "PAN x2", "PAN x2 (control)", "CG-enhanced PAN x2",
                                "elastic CG-enhanced PAN x2", "CG-optimized PAN x2", "CG-optimized PAN x2 (scratch)",
                                "CG-enhanced PAN x2 MMP", "CG-enhanced PAN x2 uniform width",
                                "CG-optimized PAN x2 hybrid"})
    EXPECT_NE(report.find("| " + row + " "), std::string::npos) << row << "\n" << report;
  const auto results = read_json(out / "results.json");
  EXPECT_GE(results["verdict"]["checks"].size(), 15u);
  EXPECT_NE(first.out.find("verdict:"), std::string::npos);

  // The held-out scene, rendered at the training data's sizes, has its own section with every
  // model and classic baseline (quality only), and the verdict checks each network against
  // bicubic there.
  EXPECT_TRUE(fs::exists(out / "heldout" / "1_heldout" / "data" / "128x96"));  // its config says 32x24, 64x48
  EXPECT_FALSE(fs::exists(out / "heldout" / "1_heldout" / "data" / "32x24"));
  const size_t section = report.find("## Held-out scene: tiny-heldout");
  ASSERT_NE(section, std::string::npos) << report;
  for (const std::string row : {"bicubic", "nearest", "PAN x2", "PAN x2 (control)", "CG-enhanced PAN x2", "CG-optimized PAN x2",
                                "CG-optimized PAN x2 (scratch)", "CG-enhanced PAN x2 MMP", "CG-optimized PAN x2 hybrid"})
    EXPECT_NE(report.find("| " + row + " ", section), std::string::npos) << row << "\n" << report;
  // The page: the verdict's checks, and pictures of the test frames and of the held-out scene.
  const auto page = out / "report" / "index.html";
  const std::string html = slurp(page);
  EXPECT_NE(html.find("Verdict:"), std::string::npos);
  EXPECT_NE(html.find("plot_tiny_x2.svg"), std::string::npos);
  EXPECT_TRUE(missing_links(page).empty()) << missing_links(page).front();
  const auto comparisons = read_json(out / "report" / "results.json")["comparisons"];
  ASSERT_GE(comparisons.size(), 2u);
  EXPECT_EQ(comparisons.back()["dataset"], "tiny-heldout");
  int heldout_checks = 0;
  for (const auto& check : results["verdict"]["checks"])
    heldout_checks += check["claim"].get<std::string>().find("on held-out scene 'tiny-heldout'") != std::string::npos;
  EXPECT_EQ(heldout_checks, 6);  // PAN, its control, CG-enhanced, CG-optimized, the hybrid; against scratch

  // A rerun finds every stage finished.
  const CliResult again = run_cgsr(args);
  ASSERT_EQ(again.exit_code, 0) << again.err;
  for (const auto& [stage, action] : stage_actions(again.err)) EXPECT_EQ(action, "skipped") << stage;
  EXPECT_EQ(stage_actions(again.err).size(), 13u);
  EXPECT_NE(again.out.find("verdict:"), std::string::npos);  // still printed

  // --from eval reruns eval, heldout and report only.
  expect_actions(run_cgsr(args + " --from eval"),
                 {{"prune", "skipped"}, {"export", "skipped"}, {"eval", "ran"}, {"heldout", "ran"}, {"report", "ran"}});

  // In int8 as well: the evaluated networks and the CG-optimized one get int8 rows, timed side by
  // side and in ONNX Runtime from their QDQ exports; the float32 rows stay the stages' own.
  const CliResult int8 = run_cgsr(args + " --set \"precisions=[fp32, int8]\" --set calibration.frames=2");
  expect_actions(int8, {{"prune", "skipped"}, {"export", "ran"}, {"eval", "ran"}, {"report", "ran"}});
  EXPECT_TRUE(fs::exists(out / "export" / "cg_optimized_int8.onnx"));
  std::map<std::string, int> rows;
  const auto reported = read_json(out / "report" / "results.json");
  for (const auto& e : reported["evaluations"]) {
    if (e["dataset"] != "tiny") continue;
    const std::string name = e["name"];
    ++rows[name];
    if (name == "PAN x2 int8" || name == "CG-optimized PAN x2 int8") {
      EXPECT_EQ(e["precision"], "int8");
      EXPECT_TRUE(e.contains("onnxruntime_latency_ms")) << name;
      EXPECT_TRUE(e.contains("latency_ms")) << name;
    }
  }
  for (const std::string name : {"PAN x2 int8", "CG-optimized PAN x2 int8", "CG-enhanced PAN x2 int8", "CG-optimized PAN x2"})
    EXPECT_EQ(rows[name], 1) << name;

  // A held-out scene that is the training scene is an error naming its config.
  const std::string tiny = std::string(CGSR_SOURCE_DIR) + "/configs/scenes/tiny.yaml";
  const CliResult same = run_cgsr(args + " --set \"heldout.scenes=[" + tiny + "]\"");
  EXPECT_NE(same.exit_code, 0);
  EXPECT_NE(same.err.find(tiny), std::string::npos) << same.err;
  EXPECT_NE(same.err.find("as the training data is"), std::string::npos) << same.err;

  // A changed search config reruns search and what depends on it (scratch trains as many steps
  // as the search's fine-tuning adds), not the trainings before it.
  expect_actions(run_cgsr(args + " --set search.final.schedule.steps=3"),
                 {{"train", "skipped"}, {"enhance", "skipped"}, {"control", "skipped"}, {"elastic", "skipped"},
                  {"search", "ran"}, {"prune", "ran"}, {"scratch", "ran"}, {"controls", "ran"}, {"eval", "ran"},
                  {"heldout", "ran"}, {"report", "ran"}});
  fs::remove_all(dir);
}

// The same pipeline on SPAN (a narrow one, so it stays quick): every stage runs on the branches it
// trains and the folds it deploys, and every exported file matches cgsr in the other runtimes.
TEST(RunCommand, TheWholePipelineRunsOnSpan) {
  const auto dir = scratch_dir("run-command-span");
  const auto config_file = write_config(dir);
  std::ofstream(dir / "span.yaml") << "backbone: span\nscale: 2\nblocks: 4\nwidths: {features: 12, trunk: 12, fuse: 12, "
                                      "block0_a: 12, block0_b: 12, block1_a: 12, block1_b: 12, block2_a: 12, block2_b: 12, "
                                      "block3_a: 12, block3_b: 12}\n";
  const auto out = dir / "run";
  const CliResult r = run_cgsr("run --config " + config_file.string() + " --out " + out.string() +
                               " --threads 2 --seed 3 --set train.model=" + (dir / "span.yaml").string() +
                               " --set enhance.rit.source=hr_unshuffle --set enhance.geometry.enabled=false");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto actions = stage_actions(r.err);
  EXPECT_EQ(actions.size(), 13u) << r.err;
  for (const auto& [stage, action] : actions) EXPECT_EQ(action, "ran") << stage;
  EXPECT_EQ(read_json(out / "search" / "results.json")["pick"]["spec"].get<std::string>().rfind("span x2", 0), 0u);
  // The pick keeps SPAN's first and last block, whatever it skips.
  const auto blocks = read_json(out / "search" / "results.json")["pick"]["subnet"]["blocks"];
  ASSERT_FALSE(blocks.empty());
  EXPECT_EQ(blocks.front().get<int>(), 0);
  EXPECT_EQ(blocks.back().get<int>(), 3);
  const auto exports = read_json(out / "export" / "results.json")["exports"];
  ASSERT_GE(exports.size(), 6u);
  for (const auto& e : exports) {
    if (!e.contains("verification")) continue;
    EXPECT_EQ(e["verification"]["failed"].get<int>(), 0) << e["file"];
    EXPECT_GE(e["verification"]["passed"].get<int>(), 1) << e["file"];
  }
  EXPECT_TRUE(fs::exists(out / "export" / "pruned" / "selector.onnx"));
  fs::remove_all(dir);
}

TEST(RunCommand, StageConfigErrorsNameTheRunConfigKey) {
  const auto dir = scratch_dir("run-command-errors");
  const auto config_file = write_config(dir);
  const std::string base = "run --config " + config_file.string() + " --out " + (dir / "run").string();

  const CliResult typo = run_cgsr(base + " --set train.schedule.stepz=3");
  EXPECT_EQ(typo.exit_code, 2);
  EXPECT_NE(typo.err.find("train.schedule.stepz: unknown key 'stepz' (did you mean 'steps'?)"), std::string::npos)
      << typo.err;
  // A mistake in the last stage's section stops the run before the first stage renders anything.
  const CliResult late = run_cgsr(base + " --set prune.pool.latency_factors=[1,2]");
  EXPECT_EQ(late.exit_code, 2);
  EXPECT_NE(late.err.find("prune.pool.latency_factors: must be positive and strictly decreasing"), std::string::npos)
      << late.err;
  EXPECT_FALSE(fs::exists(dir / "run" / "data" / "manifest.yaml"));

  const CliResult filled = run_cgsr(base + " --set search.model=x.cgsr");
  EXPECT_EQ(filled.exit_code, 2);
  EXPECT_NE(filled.err.find("search.model: is filled in by cgsr run"), std::string::npos) << filled.err;

  const CliResult both = run_cgsr(base + " --set data=somewhere");
  EXPECT_EQ(both.exit_code, 2);
  EXPECT_NE(both.err.find("exactly one of 'scene'"), std::string::npos) << both.err;

  // A folder where a stage goes that cgsr run did not make is never deleted.
  const auto foreign = dir / "other" / "train";
  fs::create_directories(foreign);
  std::ofstream(foreign / "notes.txt") << "mine";
  const CliResult kept = run_cgsr("run --config " + config_file.string() + " --out " + (dir / "other").string());
  EXPECT_EQ(kept.exit_code, 2);
  EXPECT_NE(kept.err.find("exists and was not made by cgsr run"), std::string::npos) << kept.err;
  EXPECT_EQ(slurp(foreign / "notes.txt"), "mine");

  const CliResult stage = run_cgsr(base + " --from deploy");
  EXPECT_EQ(stage.exit_code, 2);
  EXPECT_NE(stage.err.find("from: must be one of: render, train"), std::string::npos) << stage.err;
  fs::remove_all(dir);
}

TEST(RunCommand, CheckReadsEverySceneConfigAndWritesNothing) {
  const auto dir = scratch_dir("run-command-check");
  const auto config_file = write_config(dir);
  const std::string base = "run --check --config " + config_file.string() + " --out " + (dir / "run").string();
  const CliResult ok = run_cgsr(base);
  ASSERT_EQ(ok.exit_code, 0) << ok.err;
  EXPECT_NE(ok.out.find("train    pan x2, 6 steps of batch 2 at 16x16 LR patches"), std::string::npos) << ok.out;
  EXPECT_NE(ok.out.find("heldout  1 scene(s), 2 frames each"), std::string::npos) << ok.out;
  EXPECT_NE(ok.out.find("cgsr run: the config is valid"), std::string::npos) << ok.out;
  EXPECT_FALSE(fs::exists(dir / "run"));
  // --data replaces the config's scene rather than clashing with it.
  const CliResult data = run_cgsr(base + " --data " + (dir / "some_data").string());
  ASSERT_EQ(data.exit_code, 0) << data.err;
  EXPECT_NE(data.out.find("data     " + (dir / "some_data").string()), std::string::npos) << data.out;
  EXPECT_EQ(data.out.find("render "), std::string::npos) << data.out;
  // The scratch control trains as long as the pick's weights did: train 6 + enhance 4 + elastic
  // 4 + fine-tuning 2, or only the last two when the elastic network starts from scratch.
  const CliResult steps = run_cgsr(base + " --set scratch.steps=0");
  EXPECT_NE(steps.out.find("scratch  the pick's architecture, 16 steps"), std::string::npos) << steps.out;
  const CliResult fresh = run_cgsr(base + " --set scratch.steps=0 --set elastic.from_scratch=true");
  EXPECT_NE(fresh.out.find("scratch  the pick's architecture, 6 steps"), std::string::npos) << fresh.out;

  // The held-out scenes are read when their stage starts, after every network has trained: a
  // mistake there is found by --check, with its file and key.
  std::ofstream(dir / "bad_heldout.yaml") << std::string(kHeldoutScene) + "framez: 3\n";
  const CliResult typo = run_cgsr(base + " --set heldout.scenes=[" + (dir / "bad_heldout.yaml").string() + "]");
  EXPECT_EQ(typo.exit_code, 2);
  EXPECT_NE(typo.err.find("bad_heldout.yaml"), std::string::npos) << typo.err;
  EXPECT_NE(typo.err.find("unknown key 'framez'"), std::string::npos) << typo.err;
  std::ofstream(dir / "set.yaml") << "name: a-set\nscenes:\n  - {config: " + (dir / "heldout.yaml").string() + "}\n";
  const CliResult scene_set = run_cgsr(base + " --set heldout.scenes=[" + (dir / "set.yaml").string() + "]");
  EXPECT_EQ(scene_set.exit_code, 2);
  EXPECT_NE(scene_set.err.find("is a scene set"), std::string::npos) << scene_set.err;

  // The training stages' networks are built: a spec out of range, or a RIT reading an unknown
  // channel, would otherwise stop the run at its train or enhance stage, after the render.
  EXPECT_NE(ok.out.find("network  pan x2, backbone"), std::string::npos) << ok.out;
  std::ofstream(dir / "blocks0.yaml") << "backbone: pan\nscale: 2\nblocks: 0\n";
  const CliResult spec = run_cgsr(base + " --set train.model=" + (dir / "blocks0.yaml").string());
  EXPECT_EQ(spec.exit_code, 2);
  EXPECT_NE(spec.err.find("error: train: " + (dir / "blocks0.yaml").string() + ":3:9: blocks: '0' is out of range [1, 64]"),
            std::string::npos)
      << spec.err;
  const CliResult channels = run_cgsr(base + " --set 'enhance.rit.channels=[bogus]'");
  EXPECT_EQ(channels.exit_code, 2);
  EXPECT_NE(channels.err.find("error: enhance: "), std::string::npos) << channels.err;
  EXPECT_NE(channels.err.find("unknown channel 'bogus'"), std::string::npos) << channels.err;
  EXPECT_FALSE(fs::exists(dir / "run"));
  fs::remove_all(dir);
}

// Every pipeline config the project ships (configs/*.yaml; the folders hold other commands'
// configs), stage sections and scene configs included, parses: configs/general.yaml runs for
// hours, and a mistake in its last stage would cost them all.
TEST(RunCommand, EveryShippedPipelineConfigChecks) {
  const fs::path source = CGSR_SOURCE_DIR;
  std::vector<std::string> runs;
  for (const auto& entry : fs::directory_iterator(source / "configs"))
    if (entry.path().extension() == ".yaml") runs.push_back("--config " + entry.path().string());
  ASSERT_GE(runs.size(), 3u);
  // The OpenArena command of configs/general.yaml's header.
  runs.push_back("--config configs/general.yaml --set scene=configs/scenes/general_oa_set.yaml --set "
                 "'heldout.scenes=[configs/scenes/corridors.yaml, configs/scenes/heldout_hall.yaml, "
                 "configs/scenes/heldout_outdoor.yaml, configs/scenes/heldout_room.yaml, configs/scenes/oa_dm1.yaml, "
                 "configs/scenes/oa_dm4.yaml, configs/scenes/oa_dm5.yaml]'");
  // The configs name their scenes relative to the project root, where the README runs them.
  const fs::path here = fs::current_path();
  fs::current_path(source);
  for (const auto& run : runs) {
    const CliResult r = run_cgsr("run --check " + run);
    EXPECT_EQ(r.exit_code, 0) << run << "\n" << r.err;
    EXPECT_NE(r.out.find("cgsr run: the config is valid"), std::string::npos) << run << "\n" << r.out;
  }
  EXPECT_NE(run_cgsr("run --check " + runs.back()).out.find("heldout  7 scene(s)"), std::string::npos);
  fs::current_path(here);
}
