#pragma once
// Writes a network's inference graph (models/graph.h) as a TorchScript module: every tensor of
// the graph becomes a registered parameter (trainable) or buffer (constants such as a mean
// shift), and `forward` is TorchScript source generated op by op and compiled with
// Module::define. The saved file loads with torch::jit::load (LibTorch) and torch.jit.load
// (Python) and computes with the very kernels our forward uses.
//
//   forward(lr_color [, lr_render_info or hr_render_info]) -> sr        (export_signature.h)
//
// Attribute names are the op's module path with '.' written as "__", so
// "backbone.conv_first" + weight is `self.backbone__conv_first__weight`.

#include <torch/csrc/jit/api/module.h>

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "models/graph.h"

namespace cgsr {

struct TorchScriptOptions {
  // Stored as extra files in the archive ("cgsr/spec.yaml" ...), readable with
  // torch.jit.load(path, _extra_files={...}).
  std::vector<std::pair<std::string, std::string>> extra_files;
};

// The generated source of `forward` (a `def forward(self, ...)` block).
std::string torchscript_source(const graph::Graph& graph);

// The module with its attributes and compiled forward. Throws cgsr::Error naming the op for a
// graph op the writer cannot express, or the TorchScript compiler's message.
torch::jit::Module torchscript_module(const graph::Graph& graph);

// Builds, then saves atomically.
void write_torchscript(const std::filesystem::path& path, const graph::Graph& graph,
                       const TorchScriptOptions& options = {});

// Loads a TorchScript file with LibTorch; cgsr::Error naming the file when it does not load.
torch::jit::Module load_torchscript(const std::filesystem::path& path);

}  // namespace cgsr
