#pragma once
// ONNX Runtime (CPU) through the npm package onnxruntime-node: a node process runs
// tools/onnxruntime/run.mjs on a job of several models and input sets, exchanging raw float32
// files, so one process start serves a whole batch of verifications or a benchmark.
//
// Where the runner lives: $CGSR_ONNXRUNTIME_DIR, else tools/onnxruntime in the source tree this
// binary was built from (scripts/install-deps.sh runs `npm install --ignore-scripts` there).
// The node executable: $CGSR_NODE, else `node` in PATH.

#include <torch/types.h>

#include <filesystem>
#include <string>
#include <vector>

#include "export/export_signature.h"

namespace cgsr {

struct OrtRun {
  NamedTensors inputs;
  int warmup = 0;   // untimed runs first
  int repeats = 1;  // timed runs; the outputs are those of the last one
};

struct OrtRunResult {
  NamedTensors outputs;  // float32, or int64 (kLong) where the model outputs int64
  std::vector<double> times_ms;
};

struct OrtModelJob {
  std::filesystem::path model;
  std::vector<OrtRun> runs;
};

struct OrtModelResult {
  std::filesystem::path model;
  double load_ms = 0;
  std::string error;  // ONNX Runtime's message when the model failed to load or run; "" when fine
  std::vector<OrtRunResult> runs;
};

class OnnxRuntimeRunner {
 public:
  // Throws cgsr::Error saying how to install it when node or onnxruntime-node is missing.
  // `threads` 0 means the process-wide thread count (core/runtime.h).
  explicit OnnxRuntimeRunner(int threads = 0);

  // Empty when usable, else why not (for reports that skip instead of failing).
  static std::string unavailable_reason();

  // Runs every job in one node process. A model that fails in ONNX Runtime has its `error` set;
  // a failure of the runner itself throws.
  std::vector<OrtModelResult> run(const std::vector<OrtModelJob>& jobs) const;

  // The same, but throws cgsr::Error naming the model when ONNX Runtime rejected one.
  std::vector<OrtModelResult> run_checked(const std::vector<OrtModelJob>& jobs) const;

  const std::string& version() const { return version_; }  // set after the first run
  int threads() const { return threads_; }

 private:
  std::filesystem::path dir_, node_;
  int threads_;
  mutable std::string version_;
};

}  // namespace cgsr
