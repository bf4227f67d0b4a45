#include "export/verification.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>

#include "core/error.h"
#include "core/tensor_checks.h"
#include "core/text.h"
#include "export/onnxruntime_runner.h"
#include "export/opencv_runner.h"
#include "export/torchscript_runner.h"
#include "models/inference.h"

namespace cgsr {

const char* runtime_name(Runtime runtime) {
  switch (runtime) {
    case Runtime::OnnxRuntime: return "onnxruntime";
    case Runtime::OpenCvDnn: return "opencv-dnn";
    case Runtime::LibTorch: return "libtorch";
    case Runtime::PythonTorch: return "python-torch";
  }
  return "?";
}

Runtime runtime_from_name(const std::string& name) {
  const std::vector<Runtime> all = {Runtime::OnnxRuntime, Runtime::OpenCvDnn, Runtime::LibTorch, Runtime::PythonTorch};
  std::vector<std::string> names;
  for (auto r : all) {
    if (name == runtime_name(r)) return r;
    names.push_back(runtime_name(r));
  }
  throw Error("runtime", "unknown runtime '" + name + "' (valid: " + join(names) + ")" + did_you_mean(name, names));
}

std::vector<Runtime> runtimes_for(ExportFormat format) {
  if (format == ExportFormat::Onnx) return {Runtime::OnnxRuntime, Runtime::OpenCvDnn};
  return {Runtime::LibTorch, Runtime::PythonTorch};
}

double max_abs_error(const torch::Tensor& a, const torch::Tensor& b) {
  if (!a.defined() || !b.defined() || a.sizes() != b.sizes()) return std::numeric_limits<double>::infinity();
  const auto diff = (a.to(torch::kDouble) - b.to(torch::kDouble)).abs();
  if (diff.numel() == 0) return 0;
  if (torch::isnan(diff).any().item<bool>()) return std::numeric_limits<double>::infinity();
  return diff.max().item<double>();
}

NamedTensors inputs_from_batch(const SRNetworkImpl& net, const Batch& batch, const torch::Tensor& previous) {
  return export_inputs(export_signature(net.describe(false)), batch.lr_color, net.info_input(batch, previous));
}

void add_verify_inputs(VerifyCase& c, SRNetworkImpl& net, const NamedTensors& inputs,
                       const ReferenceForward& forward, const std::string& name) {
  const auto signature = export_signature(net.describe(false));
  check_inputs(signature, inputs);
  c.inputs.push_back(inputs);
  c.input_names.resize(c.inputs.size() - 1);
  c.input_names.push_back(name);
  const torch::Tensor color = find_tensor(inputs, kExportColorInput), info = info_tensor(signature, inputs);
  c.expected.push_back(forward ? forward(color, info) : infer(net, color, info));
}

VerifyCase make_verify_case(SRNetworkImpl& net, const ExportedModel& exported,
                            const std::vector<std::pair<int64_t, int64_t>>& sizes, uint64_t seed,
                            const ReferenceForward& forward) {
  VerifyCase c;
  c.label = spec_summary(net.spec());
  c.file = exported.file;
  c.format = exported.format;
  for (size_t i = 0; i < sizes.size(); ++i)
    add_verify_inputs(c, net, random_inputs(exported.signature, sizes[i].first, sizes[i].second, seed + i), forward);
  return c;
}

namespace {

std::string size_of(const NamedTensors& inputs) {
  const torch::Tensor color = find_tensor(inputs, kExportColorInput);
  if (!color.defined() || color.dim() != 4) return "?";
  return std::to_string(color.size(3)) + "x" + std::to_string(color.size(2));
}

torch::Tensor output_named(const NamedTensors& outputs, const std::string& file) {
  const torch::Tensor t = find_tensor(outputs, kExportOutput);
  if (!t.defined()) throw Error(file, std::string("the runtime produced no output '") + kExportOutput + "'");
  return t;
}

// Why `runtime` cannot run this case, or "".
std::string cannot_run(const VerifyCase& c, Runtime runtime) {
  const auto allowed = runtimes_for(c.format);
  if (std::find(allowed.begin(), allowed.end(), runtime) == allowed.end())
    return std::string(runtime_name(runtime)) + " does not run " + enum_name(c.format) + " files";
  switch (runtime) {
    case Runtime::OnnxRuntime: return OnnxRuntimeRunner::unavailable_reason();
    case Runtime::OpenCvDnn: return opencv_dnn_unsupported_reason(c.file);
    case Runtime::LibTorch: return "";
    case Runtime::PythonTorch: {
      static const std::string reason = python_torch_unavailable_reason();
      return reason;
    }
  }
  return "";
}

}  // namespace

VerifyReport verify_exports(const std::vector<VerifyCase>& cases, const VerifyOptions& options) {
  VerifyReport report;
  report.tolerance = options.tolerance;
  // Checks are laid out case by case, runtime by runtime, input by input, and filled below.
  struct Slot {
    size_t case_index;
    Runtime runtime;
    size_t first_check;  // index of the check of input 0
  };
  std::vector<Slot> slots;
  for (size_t ci = 0; ci < cases.size(); ++ci) {
    const VerifyCase& c = cases[ci];
    if (c.inputs.empty() || c.inputs.size() != c.expected.size())
      throw Error(c.file.string(), "a verification case needs input sets, each with its expected output",
                  ErrorKind::Internal);
    const bool explicit_runtimes = !options.runtimes.empty();
    for (Runtime runtime : explicit_runtimes ? options.runtimes : runtimes_for(c.format)) {
      const std::string why = cannot_run(c, runtime);
      if (!why.empty() && explicit_runtimes)
        throw Error(c.file.string(), std::string("cannot verify in ") + runtime_name(runtime) + ": " + why);
      slots.push_back({ci, runtime, report.checks.size()});
      for (size_t i = 0; i < c.inputs.size(); ++i) {
        RuntimeCheck check;
        check.label = c.label;
        check.file = c.file;
        check.runtime = runtime;
        const std::string name = i < c.input_names.size() ? c.input_names[i] : "";
        check.input = name.empty() ? size_of(c.inputs[i]) : name + " (" + size_of(c.inputs[i]) + ")";
        check.skipped = why;
        report.checks.push_back(check);
      }
    }
  }
  const auto record = [&](RuntimeCheck& check, const torch::Tensor& got, const torch::Tensor& expected) {
    check.ran = true;
    check.max_abs_error = max_abs_error(got, expected);
    check.passed = check.max_abs_error <= options.tolerance;
    if (got.defined() && got.sizes() != expected.sizes())
      check.error = "output " + shape_string(got) + " differs from ours " + shape_string(expected);
  };

  // ONNX Runtime: one node process for everything.
  std::vector<OrtModelJob> ort_jobs;
  std::vector<size_t> ort_slots;
  for (size_t s = 0; s < slots.size(); ++s) {
    const auto& slot = slots[s];
    if (slot.runtime != Runtime::OnnxRuntime || !report.checks[slot.first_check].skipped.empty()) continue;
    OrtModelJob job;
    job.model = cases[slot.case_index].file;
    for (const auto& inputs : cases[slot.case_index].inputs) job.runs.push_back({inputs, 0, 1});
    ort_jobs.push_back(job);
    ort_slots.push_back(s);
  }
  if (!ort_jobs.empty()) {
    const auto results = OnnxRuntimeRunner(options.threads).run(ort_jobs);
    for (size_t j = 0; j < results.size(); ++j) {
      const Slot& slot = slots[ort_slots[j]];
      const VerifyCase& c = cases[slot.case_index];
      for (size_t i = 0; i < c.inputs.size(); ++i) {
        RuntimeCheck& check = report.checks[slot.first_check + i];
        if (!results[j].error.empty()) {
          check.error = results[j].error;
          continue;
        }
        try {
          record(check, output_named(results[j].runs.at(i).outputs, c.file.string()), c.expected[i]);
        } catch (const Error& e) {
          check.error = e.what();
        }
      }
    }
  }

  // Python: one python3 process for everything.
  std::vector<PythonTorchJob> py_jobs;
  std::vector<size_t> py_slots;
  for (size_t s = 0; s < slots.size(); ++s) {
    const auto& slot = slots[s];
    if (slot.runtime != Runtime::PythonTorch || !report.checks[slot.first_check].skipped.empty()) continue;
    py_jobs.push_back({cases[slot.case_index].file, cases[slot.case_index].inputs});
    py_slots.push_back(s);
  }
  if (!py_jobs.empty()) {
    const auto results = run_torchscript_python(py_jobs);
    for (size_t j = 0; j < results.size(); ++j) {
      const Slot& slot = slots[py_slots[j]];
      const VerifyCase& c = cases[slot.case_index];
      for (size_t i = 0; i < c.inputs.size(); ++i) {
        RuntimeCheck& check = report.checks[slot.first_check + i];
        if (!results[j].error.empty() || i >= results[j].outputs.size())
          check.error = results[j].error.empty() ? "no output" : results[j].error;
        else
          record(check, results[j].outputs[i], c.expected[i]);
      }
    }
  }

  // In-process runtimes.
  for (const auto& slot : slots) {
    if (slot.runtime != Runtime::OpenCvDnn && slot.runtime != Runtime::LibTorch) continue;
    const VerifyCase& c = cases[slot.case_index];
    for (size_t i = 0; i < c.inputs.size(); ++i) {
      RuntimeCheck& check = report.checks[slot.first_check + i];
      if (!check.skipped.empty()) continue;
      try {
        const torch::Tensor got = slot.runtime == Runtime::OpenCvDnn
                                      ? output_named(run_opencv_dnn(c.file, c.inputs[i]), c.file.string())
                                      : run_torchscript_libtorch(c.file, c.inputs[i]);
        record(check, got, c.expected[i]);
      } catch (const Error& e) {
        check.error = e.what();
      }
    }
  }
  return report;
}

int VerifyReport::passed() const {
  return static_cast<int>(std::count_if(checks.begin(), checks.end(), [](const auto& c) { return c.ran && c.passed; }));
}
int VerifyReport::skipped() const {
  return static_cast<int>(std::count_if(checks.begin(), checks.end(), [](const auto& c) { return !c.skipped.empty(); }));
}
int VerifyReport::failed() const { return static_cast<int>(checks.size()) - passed() - skipped(); }

std::string VerifyReport::table() const {
  std::string out;
  char line[512];
  size_t label_width = 5, input_width = 9;
  for (const auto& c : checks) {
    label_width = std::max(label_width, c.label.size());
    input_width = std::max(input_width, c.input.size());
  }
  const int lw = static_cast<int>(label_width), iw = static_cast<int>(input_width);
  std::snprintf(line, sizeof line, "%-*s  %-13s %-*s %-12s %s\n", lw, "model", "runtime", iw, "input", "max |error|",
                "result");
  out += line;
  for (const auto& c : checks) {
    std::string result, error = "-";
    if (!c.skipped.empty()) {
      result = "skipped: " + c.skipped;
    } else if (!c.ran) {
      result = "FAILED: " + c.error;
    } else {
      char e[32];
      std::snprintf(e, sizeof e, "%.3g", c.max_abs_error);
      error = e;
      result = c.passed ? "ok" : "FAILED (tolerance " + std::to_string(tolerance) + ")" + (c.error.empty() ? "" : ": " + c.error);
    }
    std::snprintf(line, sizeof line, "%-*s  %-13s %-*s %-12s ", lw, c.label.c_str(), runtime_name(c.runtime), iw,
                  c.input.c_str(), error.c_str());
    out += line + result + "\n";
  }
  return out;
}

nlohmann::ordered_json VerifyReport::to_json() const {
  nlohmann::ordered_json j;
  j["tolerance"] = tolerance;
  j["passed"] = passed();
  j["failed"] = failed();
  j["skipped"] = skipped();
  j["checks"] = nlohmann::ordered_json::array();
  for (const auto& c : checks) {
    nlohmann::ordered_json e;
    e["label"] = c.label;
    e["file"] = c.file.string();
    e["runtime"] = runtime_name(c.runtime);
    e["input"] = c.input;
    if (!c.skipped.empty()) {
      e["skipped"] = c.skipped;
    } else {
      e["ran"] = c.ran;
      if (c.ran) e["max_abs_error"] = std::isfinite(c.max_abs_error) ? nlohmann::ordered_json(c.max_abs_error) : nullptr;
      e["passed"] = c.ran && c.passed;
      if (!c.error.empty()) e["error"] = c.error;
    }
    j["checks"].push_back(e);
  }
  return j;
}

}  // namespace cgsr
