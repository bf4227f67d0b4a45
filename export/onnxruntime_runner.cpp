#include "export/onnxruntime_runner.h"

#include <torch/torch.h>

#include <cstdlib>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/runtime.h"
#include "export/raw_tensor.h"
#include "export/external_runner.h"
#include "export/subprocess.h"

namespace cgsr {
namespace {
namespace fs = std::filesystem;

const char* kInstallHint = "install it with scripts/install-deps.sh (npm install --ignore-scripts in tools/onnxruntime)";

fs::path runner_dir() {
  if (const char* env = std::getenv("CGSR_ONNXRUNTIME_DIR"); env && *env) return env;
  return CGSR_ONNXRUNTIME_DIR;
}

std::string node_name() {
  if (const char* env = std::getenv("CGSR_NODE"); env && *env) return env;
  return "node";
}

std::string find_problem(const fs::path& dir) {
  if (!find_executable(node_name())) return "Node.js ('" + node_name() + "') is not installed; " + kInstallHint;
  if (!fs::exists(dir / "run.mjs")) return "the ONNX Runtime runner " + (dir / "run.mjs").string() + " is missing";
  if (!fs::exists(dir / "node_modules" / "onnxruntime-node" / "package.json"))
    return "the npm package onnxruntime-node is not installed in " + dir.string() + "; " + kInstallHint;
  return "";
}
}  // namespace

std::string OnnxRuntimeRunner::unavailable_reason() { return find_problem(runner_dir()); }

OnnxRuntimeRunner::OnnxRuntimeRunner(int threads) : dir_(runner_dir()), threads_(threads > 0 ? threads : thread_count()) {
  const std::string problem = find_problem(dir_);
  if (!problem.empty()) throw Error("ONNX Runtime", problem);
  node_ = *find_executable(node_name());
}

std::vector<OrtModelResult> OnnxRuntimeRunner::run(const std::vector<OrtModelJob>& jobs) const {
  const ExternalJob external("ONNX Runtime", "cgsr-ort");
  nlohmann::ordered_json job;
  job["threads"] = threads_;
  job["models"] = nlohmann::ordered_json::array();
  for (size_t m = 0; m < jobs.size(); ++m) {
    nlohmann::ordered_json model;
    model["path"] = fs::absolute(jobs[m].model).string();
    model["runs"] = nlohmann::ordered_json::array();
    for (size_t r = 0; r < jobs[m].runs.size(); ++r) {
      const OrtRun& run = jobs[m].runs[r];
      const std::string stem = "m" + std::to_string(m) + "_r" + std::to_string(r);
      nlohmann::ordered_json entry;
      entry["inputs"] = external.write_inputs(run.inputs, stem);
      entry["output_prefix"] = external.file(stem + ".out").string();
      entry["warmup"] = run.warmup;
      entry["repeats"] = run.repeats;
      model["runs"].push_back(entry);
    }
    job["models"].push_back(model);
  }
  const nlohmann::json result = external.run(job, {node_.string(), (dir_ / "run.mjs").string()});
  version_ = result.value("onnxruntime", "unknown");
  std::vector<OrtModelResult> out;
  const auto& models = result.at("models");
  CGSR_CHECK(models.size() == jobs.size(), "ONNX Runtime runner returned a different number of models");
  for (size_t m = 0; m < jobs.size(); ++m) {
    const auto& entry = models[m];
    OrtModelResult r;
    r.model = jobs[m].model;
    r.load_ms = entry.value("load_ms", 0.0);
    if (!entry.at("error").is_null()) r.error = entry.at("error").get<std::string>();
    if (r.error.empty()) {
      CGSR_CHECK(entry.at("runs").size() == jobs[m].runs.size(), "ONNX Runtime runner skipped runs");
      for (const auto& run : entry.at("runs")) {
        OrtRunResult rr;
        rr.times_ms = run.at("times_ms").get<std::vector<double>>();
        for (const auto& o : run.at("outputs")) {
          const std::string type = o.value("type", "float32"), file = o.at("file").get<std::string>();
          const auto shape = o.at("shape").get<std::vector<int64_t>>();
          if (type != "float32" && type != "int64")
            throw Error(jobs[m].model.string(), "ONNX Runtime output '" + o.at("name").get<std::string>() +
                                                    "' is " + type + "; the runner reads float32 and int64 only");
          rr.outputs.emplace_back(o.at("name").get<std::string>(),
                                  type == "int64" ? read_raw_int64(file, shape) : read_raw_float32(file, shape));
        }
        r.runs.push_back(std::move(rr));
      }
    }
    out.push_back(std::move(r));
  }
  return out;
}

std::vector<OrtModelResult> OnnxRuntimeRunner::run_checked(const std::vector<OrtModelJob>& jobs) const {
  auto results = run(jobs);
  for (const auto& r : results)
    if (!r.error.empty()) throw Error(r.model.string(), "ONNX Runtime: " + r.error);
  return results;
}

}  // namespace cgsr
