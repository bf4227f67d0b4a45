// The cost of training an elastic network's subnets (train/elastic_training.h): forward and
// backward of PAN x2 with a RIT on a batch of patches, as the module, as its graph with views of
// its weights (models/subnet.h), as one fixed subnet, and as a new random subnet every step (what
// the sandwich rule trains). Prints milliseconds per forward + backward for each, medians of the
// timed steps, in channels-last (the layout training measures fastest here).
//
//   bench_elastic_step [--batch 4] [--patch 24] [--steps 30] [--threads 2]
#include <CLI/CLI.hpp>
#include <torch/torch.h>

#include <chrono>
#include <cstdio>
#include <functional>
#include <random>
#include <string>

#include "core/runtime.h"
#include "core/timing.h"
#include "models/elastic.h"
#include "models/memory_layout.h"
#include "models/subnet.h"

using namespace cgsr;

int main(int argc, char** argv) {
  int batch = 4, patch = 24, steps = 30, threads = 2;
  CLI::App app{"The cost of training an elastic network's subnets, per forward + backward"};
  app.add_option("--batch", batch, "patches per step")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--patch", patch, "LR patch side, pixels")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--steps", steps, "timed steps")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--threads", threads, "LibTorch and TBB threads (0 = all hardware threads)")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  set_threads(threads);
  seed_everything(0);
  ArchSpec spec = default_spec("pan", 2);
  spec.rit.enabled = true;
  spec.rit.source = RitSource::HrUnshuffleHrFuse;
  SRNetwork net(resolve_spec(spec));
  set_parameter_layout(*net, MemoryLayout::Nhwc);
  net->train();
  const ElasticSpace space(net->spec(), ElasticOptions{});
  const auto color = to_layout(torch::rand({batch, 3, patch, patch}), MemoryLayout::Nhwc);
  const auto info = to_layout(torch::rand({batch, spec.rit.info_width(), 2 * patch, 2 * patch}), MemoryLayout::Nhwc);
  std::mt19937_64 rng(1);
  const SubnetConfig fixed = space.sample(rng);
  const auto time = [&](const std::function<torch::Tensor()>& forward) {
    std::vector<double> ms;
    for (int s = 0; s < steps + 3; ++s) {
      const auto t0 = std::chrono::steady_clock::now();
      forward().abs().mean().backward();
      const double t = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      if (s >= 3) ms.push_back(t);
    }
    return median(ms);
  };
  const auto graph_of = [&](const SubnetConfig& sub) {
    const graph::Graph g = subnet_graph(*net, sub, false, /*differentiable=*/true);
    return graph::run(g, network_inputs(g, color, info)).front().second;
  };
  std::printf("{\"module_full_ms\": %.2f, ", time([&] { return net->forward(color, info); }));
  std::printf("\"graph_full_ms\": %.2f, ", time([&] { return graph_of(space.full()); }));
  std::printf("\"fixed_subnet_ms\": %.2f, ", time([&] { return graph_of(fixed); }));
  std::printf("\"random_subnet_ms\": %.2f, ", time([&] { return graph_of(space.sample(rng)); }));
  std::printf("\"build_graph_ms\": %.2f}\n", time([&] {
    subnet_graph(*net, space.sample(rng), false, true);
    return net->rit_gate();
  }));
  return 0;
}
