#include "cli/commands/bench.h"

#include "cli/command.h"
#include "pipeline/bench.h"

namespace cgsr::cli {

void setup_bench(CLI::App& app) {
  add_command<BenchOptions>(
      app, "bench", "Time inference: median latency after warm-up, min/max, effective GFLOP/s", bench_schema,
      [](CLI::App& sub, std::vector<FlagAssignment>& flags) {
        flag_to_key(sub, flags, "--model", "model", "backbone name, spec YAML file or model file");
        flag_to_key(sub, flags, "--scale", "scale", "scale for a backbone name");
        flag_to_key(sub, flags, "--input", "input", "LR input size WxH");
        flag_to_key(sub, flags, "--batch", "batch", "images per run");
        flag_to_key(sub, flags, "--warmup", "warmup", "untimed runs first");
        flag_to_key(sub, flags, "--runs", "runs", "timed runs");
        flag_to_key(sub, flags, "--engine", "engine", "inference engine: fused or libtorch");
        list_to_key(sub, flags, "--precision", "precisions", "number formats of the fused engine: fp32, bf16, int8",
                    "PRECISION");
        flag_to_key(sub, flags, "--layout", "layout", "activation layout of the libtorch engine: auto, nchw or nhwc");
        switch_to_key(sub, flags, "--layers", "layers", "also time every layer of the network");
        switch_to_key(sub, flags, "--json", "json", "print JSON instead of a table");
        flag_to_key(sub, flags, "--onnx", "onnx", "exported ONNX file to time in ONNX Runtime as well");
      },
      [](const BenchOptions& options, const YAML::Node&, RunDir*) { return run_bench(options); },
      /*always_run_dir=*/false);
}

}  // namespace cgsr::cli
