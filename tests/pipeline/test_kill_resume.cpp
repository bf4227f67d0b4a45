// Interrupted runs: `cgsr train`, `cgsr search` and `cgsr prune` are SIGKILLed mid-run (no
// destructor runs, nothing is flushed), then rerun with --resume. A kill must never leave a file
// that looks finished but is not (results.json, a model that fails to load, a complete-looking
// log.txt), and the resumed run must finish with exactly the result of an uninterrupted run with
// the same seed: the point of checkpoints is that a long training or search can be interrupted
// without changing what it produces.
//
// Each test first runs the command uninterrupted (the reference), then kills a second run in a
// new directory as soon as its first checkpoint exists, and resumes it. Runs use one thread and
// name their memory layout (auto measures, and could choose differently in the two runs), so a
// resumed run can be compared bit for bit with the reference.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <algorithm>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>

#include "core/error.h"
#include "models/model_file.h"
#include "pruning/hybrid_model.h"
#include "tests/support/child_process.h"

using namespace cgsr;
using namespace cgsr::test;
namespace fs = std::filesystem;
using namespace std::chrono_literals;

namespace {

const std::string kSeed = "7";
// One thread: deterministic (the comparisons below are exact), and these tiny batches run faster
// on one thread than on two on a loaded 2-core machine.
const std::string kThreads = "1";
constexpr auto kTimeout = 120s;  // for the first checkpoint to appear (normally well under 5 s)

std::vector<std::string> with_run_flags(std::vector<std::string> args, const fs::path& out) {
  args.insert(args.end(), {"--out", out.string(), "--seed", kSeed, "--threads", kThreads});
  return args;
}

// Starts `args` (output captured under `log_dir`) and SIGKILLs it as soon as `written()` holds.
// Fails when that does not happen in time, or when the run ends before the kill.
void kill_when(const std::vector<std::string>& args, const fs::path& log_dir, const std::function<bool()>& written) {
  CgsrProcess run(args, log_dir);
  ASSERT_TRUE(run.wait_for(written, kTimeout)) << run.err();
  ASSERT_TRUE(run.kill()) << "the run finished before it could be killed; lengthen its schedule";
}

std::vector<std::string> with_resume(std::vector<std::string> args) {
  args.push_back("--resume");
  return args;
}

// Complete lines of a text file (the count of '\n').
int line_count(const fs::path& path) {
  const std::string text = slurp(path);
  return static_cast<int>(std::count(text.begin(), text.end(), '\n'));
}

// The tiny scene (6 frames, 64x48 -> 128x96).
fs::path render_tiny(const fs::path& dir) {
  const auto data = dir / "data";
  const auto r = run_cgsr_args(
      with_run_flags({"render", "--config", std::string(CGSR_SOURCE_DIR) + "/configs/scenes/tiny.yaml"}, data),
      dir / "render");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return data;
}

// A PAN x2 with 4 blocks: the backbone of the kill/resume runs (a quarter of the default's cost).
fs::path write_pan_spec(const fs::path& dir) {
  const auto spec = dir / "pan_x2_4blocks.yaml";
  std::ofstream(spec) << "backbone: pan\nscale: 2\nblocks: 4\n";
  return spec;
}

// A briefly trained CG-enhanced PAN x2 (RIT block and geometry head): the parent of a search and
// the input of pruning.
fs::path train_cg_parent(const fs::path& dir, const fs::path& data) {
  const auto out = dir / "parent";
  const auto r = run_cgsr_args(
      with_run_flags({"train", "--data", data.string(), "--model", write_pan_spec(dir).string(), "--set",
                      "enhance.enabled=true", "--set", "enhance.rit.width=8", "--set", "enhance.geometry.enabled=true",
                      "--set", "enhance.geometry.width=8", "--steps", "10", "--set", "schedule.batch_size=2", "--set",
                      "schedule.patch_size=16", "--set", "schedule.validate_every=0", "--set", "schedule.val_frames=1"},
                     out),
      dir / "parent");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return out / "model.cgsr";
}

// A CG-enhanced network trained briefly as an elastic network, with its latency table.
fs::path train_elastic(const fs::path& dir, const fs::path& data) {
  const auto parent = train_cg_parent(dir, data);
  const auto out = dir / "elastic";
  const auto r = run_cgsr_args(
      with_run_flags({"train", "--data", data.string(), "--model", parent.string(), "--set", "elastic.enabled=true",
                      "--set", "elastic.space={quantum: 2, min_width_fraction: 0.25, min_blocks: 1}", "--set",
                      "elastic.latency={runs: 1, calibration_subnets: 2, check_subnets: 1, subnet_runs: 1}",
                      "--steps", "10", "--set", "schedule.batch_size=2", "--set", "schedule.patch_size=16", "--set",
                      "schedule.validate_every=0", "--set", "schedule.val_frames=1"},
                     out),
      dir / "elastic");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return out / "model.cgsr";
}

// What a killed run may leave: never results.json or a log.txt that looks complete; a model file
// only when it is whole. Its log.txt.partial holds the log up to the kill (`logged`: a line the
// run wrote well before it was killed), which is what tells a user how far the run got.
void expect_killed_run_dir(const fs::path& out, const std::vector<std::string>& model_files,
                           const std::string& logged) {
  EXPECT_FALSE(fs::exists(out / "results.json"));
  EXPECT_FALSE(fs::exists(out / "log.txt"));
  ASSERT_TRUE(fs::exists(out / "log.txt.partial"));
  EXPECT_NE(slurp(out / "log.txt.partial").find(logged), std::string::npos)
      << "log.txt.partial lacks '" << logged << "':\n" << slurp(out / "log.txt.partial");
  EXPECT_TRUE(fs::exists(out / "config.yaml"));
  for (const auto& name : model_files) {
    if (!fs::exists(out / name)) continue;
    try {
      load_model(out / name);
    } catch (const Error& e) {
      ADD_FAILURE() << name << " was left behind and does not load: " << e.what();
    }
  }
}

// A finished run directory: results and the renamed log, no partial log.
void expect_finished_run_dir(const fs::path& out) {
  EXPECT_TRUE(fs::exists(out / "results.json"));
  EXPECT_TRUE(fs::exists(out / "log.txt"));
  EXPECT_FALSE(fs::exists(out / "log.txt.partial"));
}

// The step a resumed run logged ("resuming from <checkpoint> at step N/M"), -1 when it did not.
int resumed_at(const std::string& log) {
  std::smatch m;
  if (!std::regex_search(log, m, std::regex(R"(resuming from \S+ at step (\d+)/\d+)"))) return -1;
  return std::stoi(m[1]);
}

// Same parameter names, shapes and values (bit for bit).
void expect_same_weights(const fs::path& a, const fs::path& b) {
  const ModelFileContents x = read_model_file(a), y = read_model_file(b);
  ASSERT_EQ(x.tensors.size(), y.tensors.size()) << a << " vs " << b;
  for (size_t i = 0; i < x.tensors.size(); ++i) {
    EXPECT_EQ(x.tensors[i].first, y.tensors[i].first);
    EXPECT_TRUE(x.tensors[i].second.sizes() == y.tensors[i].second.sizes() &&
                torch::equal(x.tensors[i].second, y.tensors[i].second))
        << x.tensors[i].first << " differs between " << a << " and " << b;
  }
}

std::vector<double> history_psnrs(const nlohmann::json& training) {
  std::vector<double> out;
  for (const auto& h : training["history"]) out.push_back(h["psnr"]);
  return out;
}

}  // namespace

// Killed at its first checkpoint (step 20, right after a validation, so the checkpoint carries
// best weights and validation history as well as weights, optimizer state and RNG state).
TEST(KillResume, TrainResumesFromItsCheckpointToTheUninterruptedResult) {
  const auto dir = scratch_dir("kill-resume-train");
  const auto data = render_tiny(dir);
  const std::vector<std::string> train = {"train", "--data", data.string(), "--model", write_pan_spec(dir).string(),
                                          "--steps", "150", "--set", "schedule.batch_size=2", "--set",
                                          "schedule.patch_size=16", "--set", "schedule.validate_every=20", "--set",
                                          "schedule.val_frames=1", "--set", "schedule.checkpoint_every=20", "--set",
                                          "schedule.layout=nhwc"};
  const auto reference = dir / "reference", out = dir / "run";
  auto r = run_cgsr_args(with_run_flags(train, reference), dir / "reference");
  ASSERT_EQ(r.exit_code, 0) << r.err;

  ASSERT_NO_FATAL_FAILURE(
      kill_when(with_run_flags(train, out), dir / "killed", [&] { return fs::exists(out / "checkpoint.pt"); }));
  expect_killed_run_dir(out, {"model.cgsr", "last.cgsr"}, "] training ");
  EXPECT_TRUE(fs::exists(out / "checkpoint.pt"));

  r = run_cgsr_args(with_resume(with_run_flags(train, out)), dir / "resumed");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The checkpoint was read, not ignored: training went on from where it was killed.
  const int step = resumed_at(r.err);
  EXPECT_GE(step, 20) << r.err;
  EXPECT_LT(step, 150) << r.err;
  expect_finished_run_dir(out);

  const auto expected = read_json(reference / "results.json"), got = read_json(out / "results.json");
  EXPECT_EQ(got["training"]["steps"], 150);
  EXPECT_EQ(got["training"]["resumed"], true);
  EXPECT_EQ(got["training"]["best"]["step"], expected["training"]["best"]["step"]);
  EXPECT_EQ(history_psnrs(got["training"]), history_psnrs(expected["training"]));
  EXPECT_EQ(got["training"]["history"].size(), 8u);  // steps 20, 40, ..., 140 and the last, 150
  EXPECT_NO_THROW(load_model(out / "model.cgsr"));
  expect_same_weights(reference / "model.cgsr", out / "model.cgsr");  // best validation weights
  expect_same_weights(reference / "last.cgsr", out / "last.cgsr");    // final step weights
  fs::remove_all(dir);
}

TEST(KillResume, SearchResumedTwiceMakesTheUninterruptedPick) {
  const auto dir = scratch_dir("kill-resume-search");
  const auto data = render_tiny(dir);
  const auto elastic = train_elastic(dir, data);
  // 6 generations of 30 subnets, scored on 8 crops: long enough to be killed between generations.
  const auto config = dir / "search.yaml";
  std::ofstream(config) << R"(population: 30
generations: 6
baseline: ""
crops: {frames: 2, crops_per_frame: 4, size: 24, margin: 4}
pick: {latency_fraction: 0.6, measure_runs: 0}
final:
  schedule: {steps: 60, batch_size: 2, patch_size: 16, validate_every: 20, val_frames: 1, checkpoint_every: 5, layout: nhwc}
)";
  // The pick is chosen by the latency table alone here: timings differ between two runs, so a
  // measured pick need not match the uninterrupted run's (its resumption is checked at the end).
  const std::vector<std::string> search = {"search", "--config", config.string(), "--model", elastic.string(),
                                           "--data", data.string()};
  const auto reference = dir / "reference", out = dir / "run";
  auto r = run_cgsr_args(with_run_flags(search, reference), dir / "reference");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_EQ(line_count(reference / "history.jsonl"), 180);

  const auto resume = with_resume(with_run_flags(search, out));
  // Killed during the search (after its first generation is recorded) ...
  ASSERT_NO_FATAL_FAILURE(kill_when(with_run_flags(search, out), dir / "killed1",
                                    [&] { return line_count(out / "history.jsonl") >= 30; }));
  expect_killed_run_dir(out, {"model.cgsr", "subnet.cgsr"}, "] search: ");
  EXPECT_LT(line_count(out / "history.jsonl"), 180);
  ASSERT_FALSE(fs::exists(out / "final_checkpoint.pt"));  // the next kill waits for it
  // ... then, resumed, killed again during the fine-tuning of the pick ...
  ASSERT_NO_FATAL_FAILURE(
      kill_when(resume, dir / "killed2", [&] { return fs::exists(out / "final_checkpoint.pt"); }));
  expect_killed_run_dir(out, {"model.cgsr"}, "] search: pick ");
  EXPECT_EQ(line_count(out / "history.jsonl"), 180);
  // ... and resumed to the end.
  r = run_cgsr_args(resume, dir / "resumed");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_GT(resumed_at(r.err), 0) << r.err;
  expect_finished_run_dir(out);

  // Every history line is a whole JSON object, each subnet once, and the same subnets with the
  // same scores as the uninterrupted search (a subnet scored twice would show here).
  std::vector<nlohmann::json> expected_lines, lines;
  {
    std::ifstream a(reference / "history.jsonl"), b(out / "history.jsonl");
    for (std::string line; std::getline(a, line);) expected_lines.push_back(nlohmann::json::parse(line));
    for (std::string line; std::getline(b, line);) {
      ASSERT_NO_THROW(lines.push_back(nlohmann::json::parse(line))) << line;
    }
  }
  ASSERT_EQ(lines.size(), expected_lines.size());
  std::set<std::string> keys;
  for (size_t i = 0; i < lines.size(); ++i) {
    EXPECT_TRUE(keys.insert(lines[i]["key"].get<std::string>()).second) << "subnet recorded twice: " << lines[i]["key"];
    EXPECT_EQ(lines[i]["key"], expected_lines[i]["key"]) << i;
    EXPECT_EQ(lines[i]["score"], expected_lines[i]["score"]) << i;
  }

  const auto expected = read_json(reference / "results.json"), got = read_json(out / "results.json");
  EXPECT_EQ(got["pick"]["key"], expected["pick"]["key"]);
  EXPECT_EQ(got["searches"]["evolution"]["hypervolume"], expected["searches"]["evolution"]["hypervolume"]);
  EXPECT_EQ(got["searches"]["evolution"]["evaluations"], 180);
  EXPECT_EQ(got["final_training"]["steps"], 60);
  EXPECT_EQ(got["final_training"]["resumed"], true);
  EXPECT_EQ(history_psnrs(got["final_training"]), history_psnrs(expected["final_training"]));
  EXPECT_NO_THROW(load_model(out / "model.cgsr"));
  expect_same_weights(reference / "model.cgsr", out / "model.cgsr");

  // A pick checked by measurement is kept in pick.json: killed during its fine-tuning, the search
  // resumes with the subnet it measured.
  const auto measured = dir / "measured";
  auto timed = search;
  timed.insert(timed.end(), {"--set", "pick.measure_runs=2"});
  ASSERT_NO_FATAL_FAILURE(kill_when(with_run_flags(timed, measured), dir / "killed3",
                                    [&] { return fs::exists(measured / "final_checkpoint.pt"); }));
  const auto before = read_json(measured / "pick.json");
  EXPECT_GE(before["timed"].size(), 1u);
  EXPECT_EQ(before["reference"], "the full network");
  EXPECT_GT(before["full"]["ms"].get<double>(), 0);
  EXPECT_GT(before["full"]["reference_ms"].get<double>(), 0);
  r = run_cgsr_args(with_resume(with_run_flags(timed, measured)), dir / "resumed_measured");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_GT(resumed_at(r.err), 0) << r.err;
  const auto after = read_json(measured / "results.json");
  EXPECT_EQ(after["pick"]["key"], before["key"]);
  EXPECT_EQ(after["pick"]["measured"]["timed"], before["timed"]);
  EXPECT_EQ(read_json(measured / "pick.json"), before);
  fs::remove_all(dir);
}

TEST(KillResume, PruneResumesItsFineTuning) {
  const auto dir = scratch_dir("kill-resume-prune");
  const auto data = render_tiny(dir);
  const auto elastic = train_elastic(dir, data);
  const auto searched = dir / "search";
  auto searched_run = run_cgsr_args(
      with_run_flags({"search", "--model", elastic.string(), "--data", data.string(), "--set", "population=8", "--set",
                      "generations=2", "--set", "crops.frames=1", "--set", "crops.size=16", "--set",
                      "pick.latency_fraction=0.6", "--set", "final.schedule.steps=1", "--set",
                      "final.schedule.batch_size=2", "--set", "final.schedule.patch_size=16", "--set",
                      "final.schedule.val_frames=1"},
                     searched),
      dir / "search");
  ASSERT_EQ(searched_run.exit_code, 0) << searched_run.err;
  // configs/prune/quick.yaml, smaller still: fine-tuning of 60 steps, a checkpoint every 5.
  const std::vector<std::string> prune = {
      "prune", "--config", std::string(CGSR_SOURCE_DIR) + "/configs/prune/quick.yaml", "--model", elastic.string(),
      "--search", (searched / "results.json").string(), "--data", data.string(), "--set", "selector.steps=5", "--set",
      "finetune.schedule.steps=60", "--set", "finetune.schedule.checkpoint_every=5", "--set",
      "finetune.schedule.batch_size=2", "--set", "finetune.schedule.patch_size=16", "--set",
      "finetune.schedule.layout=nhwc", "--set", "eval.latency_runs=0"};
  const auto reference = dir / "reference", out = dir / "run";
  auto r = run_cgsr_args(with_run_flags(prune, reference), dir / "reference");
  ASSERT_EQ(r.exit_code, 0) << r.err;

  ASSERT_NO_FATAL_FAILURE(
      kill_when(with_run_flags(prune, out), dir / "killed", [&] { return fs::exists(out / "finetune_patterns.pt"); }));
  expect_killed_run_dir(out, {"pruned.cgsr"}, "] pruning around ");

  r = run_cgsr_args(with_resume(with_run_flags(prune, out)), dir / "resumed");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const int step = resumed_at(r.err);
  EXPECT_GE(step, 5) << r.err;
  EXPECT_LT(step, 60) << r.err;
  expect_finished_run_dir(out);

  // The hybrid model loads both ways (plain network; network with pool and samplers) and holds
  // the weights of the uninterrupted run; every evaluation matches it.
  EXPECT_NO_THROW(load_model(out / "pruned.cgsr"));
  EXPECT_NO_THROW(load_hybrid_model(out / "pruned.cgsr"));
  expect_same_weights(reference / "pruned.cgsr", out / "pruned.cgsr");
  const auto expected = read_json(reference / "results.json"), got = read_json(out / "results.json");
  EXPECT_EQ(got["finetune"]["resumed"], true);
  EXPECT_EQ(got["finetune"]["steps"], 60);
  EXPECT_EQ(got["pruned_spec"], expected["pruned_spec"]);
  ASSERT_EQ(got["evaluations"].size(), expected["evaluations"].size());
  for (size_t i = 0; i < got["evaluations"].size(); ++i) {
    EXPECT_EQ(got["evaluations"][i]["name"], expected["evaluations"][i]["name"]);
    EXPECT_EQ(got["evaluations"][i]["psnr"], expected["evaluations"][i]["psnr"]) << got["evaluations"][i]["name"];
  }

  // An eval of the resumed hybrid model through the command line works too.
  r = run_cgsr_args(with_run_flags({"eval", "--data", data.string(), "--model", (out / "pruned.cgsr").string(), "--set",
                                    "eval.latency_runs=0"},
                                   dir / "eval"),
                    dir / "eval");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  fs::remove_all(dir);
}
