// How well the latency table (models/latency_table.h) predicts what the fused path measures:
// PAN x2 with a RIT at an LR size, its table measured and calibrated, then random subnets of its
// elastic space predicted and measured side by side, in one precision. Prints one JSON object:
// the table's size and calibration, and the mean and largest absolute prediction error (%), with
// every pair.
//
//   bench_latency_table [--width 320] [--height 240] [--subnets 20] [--runs 5] [--threads 2] [--precision int8]
#include <CLI/CLI.hpp>
#include <torch/torch.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "core/runtime.h"
#include "models/elastic.h"
#include "models/latency_table.h"
#include "models/subnet.h"

using namespace cgsr;

int main(int argc, char** argv) {
  int width = 320, height = 240, subnets = 20, runs = 5, threads = 2;
  std::string precision_name = enum_name(Precision::Fp32);
  CLI::App app{"The latency table's predictions against the fused path's measurements, on random subnets"};
  app.add_option("--width", width, "LR width, pixels")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--height", height, "LR height, pixels")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--subnets", subnets, "random subnets predicted and measured")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--runs", runs, "timed runs per measurement")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--threads", threads, "LibTorch and TBB threads (0 = all hardware threads)")->capture_default_str();
  app.add_option("--precision", precision_name, "the precision the subnets run in")
      ->check(CLI::IsMember(EnumNames<Precision>::names()))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  const Precision precision = enum_from_name<Precision>(precision_name);
  set_threads(threads);
  seed_everything(0);
  ArchSpec spec = default_spec("pan", 2);
  spec.rit.enabled = true;
  spec.rit.source = RitSource::HrUnshuffleHrFuse;
  SRNetwork net(resolve_spec(spec));
  net->eval();
  const ElasticSpace space(net->spec(), ElasticOptions{});
  LatencyTableOptions options;
  options.runs = runs;
  options.check_subnets = 0;
  const LatencyTable table = measure_latency_table(*net, space, width, height, options, precision);
  std::mt19937_64 rng(7);
  double sum = 0, worst = 0;
  std::string pairs;
  for (int i = 0; i < subnets; ++i) {
    const graph::Graph g = subnet_graph(*net, space.sample(rng));
    const double predicted = table.predict(g), measured = measure_graph_latency(g, width, height, runs, precision);
    const double error = 100.0 * std::abs(predicted - measured) / measured;
    sum += error;
    worst = std::max(worst, error);
    pairs += (i ? ", " : "") + std::string("[") + std::to_string(predicted) + ", " + std::to_string(measured) + "]";
  }
  std::printf("{\"precision\": \"%s\", \"lr_size\": [%d, %d], \"threads\": %d, \"convolution_shapes\": %zu, "
              "\"scale\": %.4f, \"element_ns\": %.4f, \"offset_ms\": %.3f, \"subnets\": %d, "
              "\"mean_abs_error_percent\": %.2f, \"max_abs_error_percent\": %.2f, \"predicted_measured_ms\": [%s]}\n",
              enum_name(precision).c_str(), width, height, threads, table.conv_ms.size(), table.scale,
              table.element_ns, table.offset_ms, subnets, sum / subnets, worst, pairs.c_str());
  return 0;
}
