#pragma once
// The interface of an exported network, the same for every format: inputs `lr_color`
// [N, 3, H, W] and, when the model uses rendering information, either `lr_render_info`
// [N, C, H, W] (RIT source lr) or `hr_render_info` [N, C, s*H, s*W] (every other source), its
// channels in render_channels.h order and depth in the spec's rit.depth_encoding; output `sr`
// [N, 3, s*H, s*W]. Read off the inference graph (models/graph.h), never off modules.

#include <ATen/core/Generator.h>
#include <torch/types.h>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "models/graph.h"

namespace cgsr {

inline constexpr const char* kExportColorInput = "lr_color";
inline constexpr const char* kExportInfoInput = "lr_render_info";
inline constexpr const char* kExportHrInfoInput = "hr_render_info";
inline constexpr const char* kExportOutput = "sr";

struct ExportPort {
  std::string name;        // lr_color, lr_render_info or hr_render_info, sr
  std::string graph_name;  // the graph's own name: color, info or info_hr, image
  int value = -1;          // graph value index
  int64_t channels = 0;
  int64_t factor = 1;                     // spatial size relative to the LR colour input
  std::vector<std::string> channel_names;  // "depth", "normal", ... for the rendering information
};

struct ExportSignature {
  std::vector<ExportPort> inputs;  // lr_color, then the rendering information when present
  const ExportPort* info_input() const;  // nullptr without rendering information
  ExportPort output;               // sr
  int64_t scale() const { return output.factor; }
  const ExportPort* find_input(const std::string& name) const;
};

// Throws cgsr::Error when the graph's inputs/outputs are not those of an inference graph
// (e.g. a training graph with a geometry output, or an unknown input).
ExportSignature export_signature(const graph::Graph& graph);

// "lr_color [1, 3, 10, 12], lr_render_info [1, 6, 10, 12] -> sr [1, 3, 20, 24]"
std::string signature_string(const ExportSignature& signature, int64_t width, int64_t height, int64_t batch = 1);

// Named inputs in export order at LR size `width` x `height`.
using NamedTensors = std::vector<std::pair<std::string, torch::Tensor>>;

// Random test inputs for a signature: colour uniform in [0,1], rendering information uniform in
// [0,1] (normals in [-1,1]); drawn from `generator_seed` so runs are reproducible.
NamedTensors random_inputs(const ExportSignature& signature, int64_t width, int64_t height, uint64_t seed,
                           int64_t batch = 1);
// One random rendering-information tensor [batch, C, height, width] of `channel_names` (render_channels.h
// order), each channel in its range as above (motion: +-4 pixels), drawn from `generator`.
torch::Tensor random_render_info(const std::vector<std::string>& channel_names, int64_t batch, int64_t height,
                                 int64_t width, at::Generator& generator);

// Checks that `inputs` are exactly the signature's inputs with the right shapes for one LR size;
// returns that size (width, height). Throws cgsr::Error naming the offending input.
std::pair<int64_t, int64_t> check_inputs(const ExportSignature& signature, const NamedTensors& inputs);

torch::Tensor find_tensor(const NamedTensors& tensors, const std::string& name);  // undefined when absent

// The exported inputs of `signature` from a colour tensor and the network's rendering information
// (SRNetworkImpl::info_input; ignored when the signature has none).
NamedTensors export_inputs(const ExportSignature& signature, const torch::Tensor& lr_color, const torch::Tensor& info);
// The rendering information among `inputs` (undefined when the signature has none).
torch::Tensor info_tensor(const ExportSignature& signature, const NamedTensors& inputs);

}  // namespace cgsr
