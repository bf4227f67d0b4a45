#include "export/torchscript_runner.h"

#include <torch/script.h>
#include <torch/torch.h>

#include <cstdlib>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/text.h"
#include "export/raw_tensor.h"
#include "export/external_runner.h"
#include "export/subprocess.h"
#include "export/torchscript_writer.h"

namespace cgsr {
namespace {
namespace fs = std::filesystem;

std::string python_name() {
  if (const char* env = std::getenv("CGSR_PYTHON"); env && *env) return env;
  return "/usr/bin/python3";
}

fs::path python_script() { return fs::path(CGSR_TOOLS_DIR) / "torchscript" / "run_torchscript.py"; }

std::string& cached_python_version() {
  static std::string version;
  return version;
}
}  // namespace

torch::Tensor run_torchscript_libtorch(const fs::path& file, const NamedTensors& inputs) {
  torch::jit::Module module = load_torchscript(file);
  const auto& schema = module.get_method("forward").function().getSchema();
  std::vector<torch::jit::IValue> args;
  std::vector<std::string> expected;
  for (size_t i = 1; i < schema.arguments().size(); ++i) {  // 0 is self
    const std::string& name = schema.arguments()[i].name();
    expected.push_back(name);
    const torch::Tensor t = find_tensor(inputs, name);
    if (!t.defined()) throw Error(file.string(), "forward takes '" + name + "', which was not given");
    args.emplace_back(t);
  }
  for (const auto& [name, t] : inputs)
    if (std::find(expected.begin(), expected.end(), name) == expected.end())
      throw Error(file.string(), "forward has no argument '" + name + "' (it takes " + join(expected) + ")");
  try {
    torch::NoGradGuard no_grad;
    return module.forward(args).toTensor();
  } catch (const c10::Error& e) {
    throw Error(file.string() + " (LibTorch)", e.what_without_backtrace());
  }
}

std::string python_torch_unavailable_reason() {
  if (!find_executable(python_name())) return "no Python interpreter at " + python_name();
  if (!fs::exists(python_script())) return "the runner " + python_script().string() + " is missing";
  const ProcessResult p = run_process({python_name(), "-c", "import torch; print(torch.__version__)"});
  if (p.exit_code != 0)
    return python_name() + " cannot import torch (install Debian's python3-torch: scripts/install-deps.sh)";
  cached_python_version() = p.out.substr(0, p.out.find_last_not_of("\n\r ") + 1);
  return "";
}

std::string python_torch_version() { return cached_python_version(); }

std::vector<PythonTorchResult> run_torchscript_python(const std::vector<PythonTorchJob>& jobs) {
  if (const std::string why = python_torch_unavailable_reason(); !why.empty()) throw Error("Python torch", why);
  const ExternalJob external("Python torch", "cgsr-python");
  nlohmann::ordered_json job;
  job["models"] = nlohmann::ordered_json::array();
  for (size_t m = 0; m < jobs.size(); ++m) {
    nlohmann::ordered_json model;
    model["path"] = fs::absolute(jobs[m].model).string();
    model["runs"] = nlohmann::ordered_json::array();
    for (size_t r = 0; r < jobs[m].runs.size(); ++r) {
      const std::string stem = "m" + std::to_string(m) + "_r" + std::to_string(r);
      nlohmann::ordered_json run;
      run["inputs"] = external.write_inputs(jobs[m].runs[r], stem);
      run["output"] = external.file(stem + ".out.f32").string();
      model["runs"].push_back(run);
    }
    job["models"].push_back(model);
  }
  const nlohmann::json result = external.run(job, {python_name(), python_script().string()});
  std::vector<PythonTorchResult> out;
  const auto& models = result.at("models");
  CGSR_CHECK(models.size() == jobs.size(), "Python runner returned a different number of models");
  for (size_t m = 0; m < jobs.size(); ++m) {
    PythonTorchResult r;
    r.model = jobs[m].model;
    if (!models[m].at("error").is_null()) r.error = models[m].at("error").get<std::string>();
    for (const auto& run : models[m].at("runs"))
      r.outputs.push_back(read_raw_float32(run.at("file").get<std::string>(), run.at("shape").get<std::vector<int64_t>>()));
    out.push_back(std::move(r));
  }
  return out;
}

}  // namespace cgsr
