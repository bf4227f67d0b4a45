// Latency of dense, statically pruned, magnitude-pruned and hybrid-pruned (static + per-frame
// dynamic patterns) networks on the same input, in one process: the targets are timed in
// interleaved rounds (one run of each per round, after warm-up), so drift on a shared machine hits
// all alike, and the medians are compared with the dense baseline's.
//
//   bench_pruning [--rounds N] [--input WxH] [--model pruned.cgsr] [--threads N]
//
// Without --model the networks are PAN x2 (published widths) with synthetic pruning: static = the
// 75% of every block-internal group with the largest weights, hybrid = that network running
// patterns that keep 50% of the original widths (the per-frame cost of keep_rate 0.5), MMP =
// magnitude pruning to 50%. With --model pruned.cgsr (written by `cgsr prune`), the real hybrid
// model, its static network and its parent model (provenance.parent) are timed instead.
#include <torch/torch.h>

#include <cstdio>
#include <cstdlib>
#include <functional>
#include <string>
#include <memory>
#include <random>

#include "core/runtime.h"
#include "core/text.h"
#include "core/timing.h"
#include "models/inference.h"
#include "models/model_file.h"
#include "pruning/hybrid_upscaler.h"
#include "pruning/magnitude_pruning.h"
#include "pruning/pattern_executor.h"

using namespace cgsr;

namespace {

// `k` random patterns per unit keeping kept_count(original width, rate) channels of each group.
PatternPool synthetic_pool(const SRNetworkImpl& net, const ArchSpec& original, double rate, int k) {
  std::mt19937 rng(7);
  PatternPool pool;
  for (const auto& u : find_units(net.describe(false))) {
    UnitPatterns up{u, {}};
    for (int i = 0; i < k; ++i) {
      Pattern p;
      for (size_t g = 0; g < u.groups.size(); ++g) {
        std::vector<int64_t> all(u.widths[g]);
        for (int64_t c = 0; c < u.widths[g]; ++c) all[c] = c;
        std::shuffle(all.begin(), all.end(), rng);
        all.resize(std::min<int64_t>(u.widths[g], kept_count(original.group_width(u.groups[g]), rate)));
        std::sort(all.begin(), all.end());
        p.keep[u.groups[g]] = all;
      }
      up.patterns.push_back(p);
    }
    pool.units.push_back(up);
  }
  return pool;
}

Batch make_frame(const std::vector<RenderChannel>& channels, int64_t w, int64_t h, int index) {
  Batch b;
  b.scale = 2;
  b.lr_color = torch::rand({1, 3, h, w});
  b.channels = channels;
  b.lr_info = torch::rand({1, static_cast<int64_t>(total_width(channels)), h, w});
  b.frames = {index};
  return b;
}

torch::Tensor pick(const Batch& b, const std::vector<RenderChannel>& wanted) {
  if (wanted.empty()) return {};
  std::vector<torch::Tensor> parts;
  for (auto c : wanted) {
    int64_t offset = 0;
    for (auto a : b.channels) {
      if (a == c) break;
      offset += channel_width(a);
    }
    parts.push_back(b.lr_info.slice(1, offset, offset + channel_width(c)));
  }
  return torch::cat(parts, 1);
}

}  // namespace

int main(int argc, char** argv) {
  int rounds = 15, threads = 0;
  std::string input = "320x180", model_path;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::runtime_error(arg + " needs a value");
      return argv[++i];
    };
    if (arg == "--rounds") rounds = std::stoi(value());
    else if (arg == "--input") input = value();
    else if (arg == "--model") model_path = value();
    else if (arg == "--threads") threads = std::stoi(value());
    else {
      std::fprintf(stderr, "usage: bench_pruning [--rounds N] [--input WxH] [--model pruned.cgsr] [--threads N]\n");
      return 2;
    }
  }
  set_threads(threads);
  torch::manual_seed(1);
  const auto [w, h] = parse_size(input, "--input");
  const auto channels = parse_channels({"depth", "normal", "normal_angle", "edge"});
  SRNetwork dense{nullptr}, static_net{nullptr}, mmp{nullptr};
  std::unique_ptr<HybridUpscaler> hybrid;
  if (!model_path.empty()) {
    HybridModel model = load_hybrid_model(model_path);
    dense = load_model(model.provenance.parent).network;
    static_net = model.network;
    mmp = magnitude_prune(*dense, 0.5).network;
    hybrid = std::make_unique<HybridUpscaler>("hybrid", std::move(model));
  } else {
    dense = SRNetwork(default_spec("pan", 2));
    static_net = magnitude_prune(*dense, 0.75).network;
    mmp = magnitude_prune(*dense, 0.5).network;
    HybridModel model;
    model.network = static_net;
    model.pool = synthetic_pool(*static_net, dense->spec(), 0.5, 8);
    model.samplers = DynamicSamplers(SamplerOptions{}, std::vector<int>(model.pool.units.size(), 8));
    hybrid = std::make_unique<HybridUpscaler>("hybrid", std::move(model));
  }
  const Batch frame = make_frame(channels, w, h, 1), previous = make_frame(channels, w, h, 0);
  struct Target {
    std::string name;
    std::function<void()> run;
  };
  std::vector<Target> targets = {
      {"dense", [&] { infer(*dense, frame.lr_color, pick(frame, dense->input_channels())); }},
      {"static", [&] { infer(*static_net, frame.lr_color, pick(frame, static_net->input_channels())); }},
      {"magnitude 0.5", [&] { infer(*mmp, frame.lr_color, pick(frame, mmp->input_channels())); }},
      {"hybrid", [&] {
         hybrid->previous_frame(previous);
         hybrid->upscale(frame);
       }},
      {"hybrid: choosing only", [&] { hybrid->choose(frame); }},
  };
  std::vector<std::function<void()>> runs;
  for (const auto& t : targets) runs.push_back(t.run);
  const auto stats = measure_latency_interleaved(runs, /*warmup=*/2, rounds);
  std::printf("input %s (x2), %d threads, %d interleaved rounds, medians\n", input.c_str(), thread_count(), rounds);
  std::printf("%-24s %12s %10s\n", "target", "median ms", "vs dense");
  for (size_t i = 0; i < targets.size(); ++i)
    std::printf("%-24s %12.3f %10.3f\n", targets[i].name.c_str(), stats[i].median_ms,
                stats[i].median_ms / stats.front().median_ms);
  return 0;
}
