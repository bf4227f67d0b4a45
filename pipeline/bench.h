#pragma once
// The bench job, what `cgsr bench` runs: inference latency of a network: the median over
// repeated runs after warm-up, min and max, and the effective throughput 2 x MACs / time.
//
// Each thing timed is a BenchTarget (a runtime + one inference on a prepared input); --model
// adds the LibTorch target. Other runtimes (e.g. an exported ONNX file) add their own target
// builder next to model_target() and run_bench() times them all the same way.

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/timing.h"
#include "models/inference.h"
#include "models/memory_layout.h"
#include "models/model_source.h"
#include "models/precision.h"
#include "pipeline/run_settings.h"

namespace cgsr {

struct BenchOptions : RunSettings {
  std::string model;              // backbone name, spec YAML or model file
  int scale = 0;                  // 0: the model file's scale, or 2 for a backbone name
  std::string input = "320x240";  // LR input WxH
  int batch = 1;
  int warmup = 3;
  int runs = 20;
  InferenceEngine engine = InferenceEngine::Fused;
  std::vector<Precision> precisions = {Precision::Fp32};  // of the fused engine, each timed in turn
  MemoryLayout layout = MemoryLayout::Auto;  // activation layout of the libtorch engine
  bool layers = false;          // also time every layer (graph interpreter, NCHW)
  bool json = false;
  std::string onnx;  // an exported ONNX file to time in ONNX Runtime on the same input
};

struct BenchTarget {
  std::string name;           // what is timed, e.g. "pan x2"
  std::string runtime;        // "libtorch", ...
  std::string detail;         // e.g. "layout nchw"
  int64_t macs = 0;           // multiply-accumulates of one run (for GFLOP/s)
  std::function<void()> run;  // one inference on the prepared input
};

struct BenchResult {
  BenchTarget target;
  LatencyStats latency;
  double gflops = 0;  // 2 * MACs / median time
};

config::Schema<BenchOptions> bench_schema();

// --model, or the spec an exported ONNX file records when only --onnx is given (latency does not
// depend on the weights).
ModelSource bench_source(const BenchOptions& options);
// The --onnx file timed in ONNX Runtime (export/onnxruntime_runner.h) on inputs of the --model shapes.
BenchResult time_onnx(const BenchOptions& options);
// The --model target of the chosen engine (the fused one at `precision`). INT8 is calibrated on
// the timed input itself: its latency does not depend on the scales.
BenchTarget model_target(const BenchOptions& options, Precision precision = Precision::Fp32);
// Mean time of each op of the --model network's graph over the timed runs, slowest first.
nlohmann::ordered_json layer_profile(const BenchOptions& options);
BenchResult time_target(const BenchTarget& target, int warmup, int runs);
nlohmann::ordered_json run_bench(const BenchOptions& options);

}  // namespace cgsr
