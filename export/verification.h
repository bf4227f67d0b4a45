#pragma once
// Verification of exported files in other runtimes against our own forward pass: ONNX files in
// ONNX Runtime (onnxruntime_runner.h) and OpenCV DNN (opencv_runner.h), TorchScript files in
// LibTorch and in Python's torch (torchscript_runner.h). A check passes when the maximum
// absolute difference to our output is within the tolerance (1e-4 by default).
//
// Several files verify together: all ONNX Runtime runs of a call share one node process and all
// Python runs one python3 process.
//
//   auto c = make_verify_case(*net, exported, {{12, 10}, {9, 7}}, /*seed=*/1);
//   VerifyReport report = verify_exports({c});
//   if (!report.ok()) ...   // report.table() for people, report.to_json() for results.json

#include <torch/types.h>

#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "export/exporter.h"
#include "render_data/batch.h"

namespace cgsr {

enum class Runtime { OnnxRuntime, OpenCvDnn, LibTorch, PythonTorch };
const char* runtime_name(Runtime runtime);  // "onnxruntime", "opencv-dnn", "libtorch", "python-torch"
Runtime runtime_from_name(const std::string& name);
std::vector<Runtime> runtimes_for(ExportFormat format);

struct VerifyCase {
  std::string label;  // for reports, e.g. "pan x2"
  std::filesystem::path file;
  ExportFormat format = ExportFormat::Onnx;
  std::vector<NamedTensors> inputs;     // one or more input sets
  std::vector<torch::Tensor> expected;  // our forward pass on each input set
  std::vector<std::string> input_names; // each set's name in reports ("frame 12"; "" for random inputs)
};

// Our side of a comparison: the network's output for LR colour and rendering information.
// Empty: the LibTorch forward pass (models/inference.h infer); an INT8 export compares with the
// fused path's INT8 run instead.
using ReferenceForward = std::function<torch::Tensor(const torch::Tensor& color, const torch::Tensor& info)>;

// Random inputs at each LR size (seeded) and our forward pass on them.
VerifyCase make_verify_case(SRNetworkImpl& net, const ExportedModel& exported,
                            const std::vector<std::pair<int64_t, int64_t>>& sizes, uint64_t seed,
                            const ReferenceForward& forward = {});

// The inputs an exported network takes for a rendered batch: lr_color and the model's own
// rendering channels at the resolution it wants (SRNetworkImpl::info_input).
// A recurrent network's `previous` output goes in as SRNetworkImpl::info_input takes it.
NamedTensors inputs_from_batch(const SRNetworkImpl& net, const Batch& batch, const torch::Tensor& previous = {});

// Adds an input set (e.g. a rendered frame, named "frame 12") with our forward pass on it.
void add_verify_inputs(VerifyCase& c, SRNetworkImpl& net, const NamedTensors& inputs,
                       const ReferenceForward& forward = {}, const std::string& name = "");

struct VerifyOptions {
  // Empty: every runtime of each file's format; one that cannot run a file (OpenCV DNN on a
  // dynamic-size export, Python without torch, ONNX Runtime not installed) is reported as
  // skipped with the reason. Named runtimes must all run: otherwise cgsr::Error.
  std::vector<Runtime> runtimes;
  double tolerance = 1e-4;
  int threads = 0;  // ONNX Runtime threads; 0 = the process-wide setting
};

struct RuntimeCheck {
  std::string label;
  std::filesystem::path file;
  Runtime runtime = Runtime::OnnxRuntime;
  std::string input;    // "12x10", or "frame 12 (64x48)" for a named input set
  bool ran = false;
  std::string skipped;  // why it did not run
  std::string error;    // the runtime's message when it failed on the file
  double max_abs_error = -1;
  bool passed = false;
};

struct VerifyReport {
  std::vector<RuntimeCheck> checks;
  double tolerance = 1e-4;
  int passed() const;
  int failed() const;
  int skipped() const;
  bool ok() const { return failed() == 0 && passed() > 0; }
  std::string table() const;
  nlohmann::ordered_json to_json() const;
};

VerifyReport verify_exports(const std::vector<VerifyCase>& cases, const VerifyOptions& options = {});

// max |a - b|; infinity when the shapes differ or either holds a NaN.
double max_abs_error(const torch::Tensor& a, const torch::Tensor& b);

}  // namespace cgsr
