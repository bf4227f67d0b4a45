#pragma once
// One job for a helper runtime in another process (tools/onnxruntime/run.mjs under node,
// tools/torchscript/run_torchscript.py under python3): input tensors as raw float32 files and a
// job.json naming them in a private temporary directory, the program run on
// `job.json result.json`, and its result.json read back. Both runners go through this, so they
// fail the same way: a runner that exits non-zero, writes no result or writes one that does not
// parse is a cgsr::Error naming the runtime.

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "export/export_signature.h"
#include "export/subprocess.h"

namespace cgsr {

class ExternalJob {
 public:
  // `runtime` names the runtime in errors ("ONNX Runtime"); `prefix` the temporary directory.
  ExternalJob(std::string runtime, const std::string& prefix);

  // Writes each tensor to a file named after `stem` and the input, and returns the entries the
  // runners read: [{name, shape, file}].
  nlohmann::ordered_json write_inputs(const NamedTensors& inputs, const std::string& stem) const;

  // A path in the job's directory, for the files the runner writes (its outputs).
  std::filesystem::path file(const std::string& name) const { return dir_.path() / name; }

  // Writes `job` as job.json, runs `program` with job.json and result.json appended, and returns
  // the parsed result.
  nlohmann::json run(const nlohmann::ordered_json& job, std::vector<std::string> program) const;

 private:
  std::string runtime_;
  TempDir dir_;
};

}  // namespace cgsr
