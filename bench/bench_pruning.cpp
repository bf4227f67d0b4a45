// Latency of a hybrid-pruned model against its own static network, per frame over a sequence of
// frames (the pattern switches as the frames change), in one process: the targets are timed in
// interleaved rounds (one frame of each per round, after warm-up), so drift on a shared machine
// hits all alike. Every target runs on cgsr's fast path (models/fused_graph.h).
//
//   bench_pruning --model runs/quickstart/prune/pruned.cgsr --data runs/quickstart/data
//     [--baseline runs/quickstart/prune/baseline0_magnitude.cgsr ...] [--split test] [--rounds N] [--threads N]
//
// Prints, per target, mean, median and p95 per frame and the mean against the static network's:
// the static network (the widest pattern), each pattern alone, each --baseline model (a static
// network at the hybrid's mean MACs, the control), and the hybrid model (choosing and running,
// frame after frame); then how often the hybrid chose each pattern.
#include <CLI/CLI.hpp>
#include <torch/torch.h>

#include <algorithm>
#include <cstdio>
#include <functional>
#include <string>

#include "core/runtime.h"
#include "core/timing.h"
#include "eval/evaluation.h"
#include "models/model_file.h"
#include "pruning/hybrid_upscaler.h"
#include "render_data/dataset.h"
#include "render_data/patch_sampler.h"

using namespace cgsr;

int main(int argc, char** argv) {
  int rounds = 20, threads = 0;
  std::string model_path, data_path, split = "test";
  std::vector<std::string> baseline_paths;
  CLI::App app{"Latency of a hybrid-pruned model against its static network, per frame over a sequence"};
  app.add_option("--model", model_path, "a hybrid-pruned model (cgsr prune's pruned.cgsr)")->required();
  app.add_option("--data", data_path, "the data set")->required();
  app.add_option("--baseline", baseline_paths, "a static model to time beside it (repeatable)");
  app.add_option("--split", split, "the split whose frames run")->capture_default_str();
  app.add_option("--rounds", rounds, "interleaved timing rounds")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--threads", threads, "LibTorch and TBB threads (0 = all hardware threads)")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  set_threads(threads);
  const Dataset data = Dataset::open(data_path);
  HybridUpscaler hybrid("hybrid", load_hybrid_model(model_path));
  const HybridModel& model = hybrid.model();
  EvalOptions eval;
  eval.split = split;
  const auto frames = evaluation_frames(data, eval);
  const int scale = model.network->spec().scale;
  // The hybrid sees each frame's predecessor first, as in evaluation (it chooses from the change).
  TimingSequence sequence;
  for (int f : frames) {
    sequence.frames.push_back(frame_batch(data, f, scale, hybrid.channels(), hybrid.depth_encoding()));
    sequence.previous.push_back(frame_batch(data, data.has_previous(f) ? f - 1 : f, scale, hybrid.channels(), hybrid.depth_encoding()));
  }
  const std::vector<Batch>& batches = sequence.frames;
  PatternNetworks patterns(*model.network, model.pool);

  // Every target runs the frames in turn; run(i) upscales frame i of the sequence.
  struct Target {
    std::string name;
    std::function<void(size_t)> run;
  };
  std::vector<Target> targets = {{"static network", [&](size_t i) {
                                    patterns.run(0, batches[i].lr_color, model.network->info_input(batches[i]));
                                  }}};
  for (int k = 1; k < patterns.size(); ++k)
    targets.push_back({"pattern " + std::to_string(k) + " alone", [&, k](size_t i) {
                         patterns.run(k, batches[i].lr_color, model.network->info_input(batches[i]));
                       }});
  // A baseline may read other rendering channels than the hybrid: its own batches of the frames.
  std::vector<std::unique_ptr<NetworkUpscaler>> baselines;
  std::vector<std::vector<Batch>> baseline_batches;
  for (const auto& path : baseline_paths) {
    Model m = load_model(path);
    const std::string name = m.provenance.extra.value("name", std::filesystem::path(path).stem().string());
    baselines.push_back(std::make_unique<NetworkUpscaler>(name, m.network));
    baseline_batches.emplace_back();
    for (int f : frames)
      baseline_batches.back().push_back(
          frame_batch(data, f, scale, baselines.back()->channels(), baselines.back()->depth_encoding()));
  }
  for (size_t b = 0; b < baselines.size(); ++b)
    targets.push_back({baselines[b]->name(), [&, b](size_t i) { baselines[b]->upscale(baseline_batches[b][i]); }});
  targets.push_back({"hybrid (choose + run)", [&](size_t i) { sequence.run(hybrid, i); }});
  std::vector<std::function<void()>> runs;
  for (const auto& t : targets) runs.push_back([&, next = size_t{0}]() mutable { t.run(next++ % batches.size()); });
  const auto stats = measure_latency_interleaved(runs, /*warmup=*/static_cast<int>(batches.size()),
                                                 rounds * static_cast<int>(batches.size()));
  std::printf("%s: %zu %s frames in turn, %d threads, %d rounds\n", model_path.c_str(), batches.size(), split.c_str(),
              thread_count(), rounds);
  std::printf("%-32s %10s %10s %10s %10s\n", "target", "mean ms", "p50 ms", "p95 ms", "mean/static");
  for (size_t i = 0; i < targets.size(); ++i)
    std::printf("%-32s %10.2f %10.2f %10.2f %10.3f\n", targets[i].name.c_str(), stats[i].mean_ms, stats[i].median_ms,
                stats[i].p95_ms, stats[i].mean_ms / stats.front().mean_ms);
  std::printf("hybrid's patterns chosen:");
  for (size_t k = 0; k < hybrid.usage().size(); ++k) std::printf(" %zu: %lld", k, static_cast<long long>(hybrid.usage()[k]));
  std::printf("\n");
  return 0;
}
