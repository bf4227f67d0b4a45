#pragma once
// Running an exported TorchScript file: in LibTorch (torch::jit::load, in process) and in
// Python (torch.jit.load through tools/torchscript/run_torchscript.py, in a python3 process
// that has Debian's python3-torch).
//
// The Python interpreter: $CGSR_PYTHON, else /usr/bin/python3 (Debian's, where python3-torch
// installs; a python3 earlier in PATH may be another installation without torch).

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "export/export_signature.h"

namespace cgsr {

// forward(**inputs) in LibTorch; inputs are matched to forward's arguments by name. Throws
// cgsr::Error naming the file for a missing/extra input or a failure inside the module.
torch::Tensor run_torchscript_libtorch(const std::filesystem::path& file, const NamedTensors& inputs);

// Empty when python3 with torch is usable, else why not.
std::string python_torch_unavailable_reason();

struct PythonTorchJob {
  std::filesystem::path model;
  std::vector<NamedTensors> runs;
};
struct PythonTorchResult {
  std::filesystem::path model;
  std::string error;  // Python's message when loading or running failed; "" when fine
  std::vector<torch::Tensor> outputs;  // one per run
};

// Runs every job in one python3 process. Throws when Python itself is unusable.
std::vector<PythonTorchResult> run_torchscript_python(const std::vector<PythonTorchJob>& jobs);

std::string python_torch_version();  // "1.13.1" or "" before the first run / when unavailable

}  // namespace cgsr
