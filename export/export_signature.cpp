#include "export/export_signature.h"

#include <torch/torch.h>

#include <ATen/CPUGeneratorImpl.h>

#include "core/error.h"
#include "core/tensor_checks.h"
#include "core/text.h"
#include "render_data/render_channels.h"

namespace cgsr {
namespace {
constexpr const char* kInfoPrefix = "info:";

ExportPort make_port(const graph::Graph& graph, const std::string& name, const std::string& graph_name, int value) {
  const graph::Value& v = graph.values.at(value);
  ExportPort port;
  port.name = name;
  port.graph_name = graph_name;
  port.value = value;
  port.channels = graph::layout_width(v.layout);
  port.factor = v.factor;
  for (const auto& segment : v.layout)
    if (segment.group.rfind(kInfoPrefix, 0) == 0) port.channel_names.push_back(segment.group.substr(5));
  return port;
}

std::string port_shape(const ExportPort& port, int64_t width, int64_t height, int64_t batch) {
  return "[" + std::to_string(batch) + ", " + std::to_string(port.channels) + ", " +
         std::to_string(height * port.factor) + ", " + std::to_string(width * port.factor) + "]";
}
}  // namespace

const ExportPort* ExportSignature::find_input(const std::string& name) const {
  for (const auto& in : inputs)
    if (in.name == name) return &in;
  return nullptr;
}

ExportSignature export_signature(const graph::Graph& graph) {
  ExportSignature s;
  for (const auto& [name, value] : graph.inputs) {
    if (name == "color")
      s.inputs.push_back(make_port(graph, kExportColorInput, name, value));
    else if (name == "info")
      s.inputs.push_back(make_port(graph, kExportInfoInput, name, value));
    else if (name == "info_hr")
      s.inputs.push_back(make_port(graph, kExportHrInfoInput, name, value));
    else
      throw Error("export", "the graph has an input '" + name +
                                "' that no export format knows (expected color, info, info_hr)");
  }
  if (s.inputs.empty() || s.inputs.front().name != kExportColorInput)
    throw Error("export", "the graph has no colour input 'color' as its first input");
  const auto& color = s.inputs.front();
  if (color.channels != 3 || color.factor != 1)
    throw Error("export", "the colour input must have 3 channels at LR size, the graph says " +
                              std::to_string(color.channels) + " channels at factor " + std::to_string(color.factor));
  if (graph.outputs.size() != 1 || graph.outputs.front().first != "image") {
    std::vector<std::string> names;
    for (const auto& [name, value] : graph.outputs) names.push_back(name);
    throw Error("export", "an exported network has the single output 'image'; this graph has " +
                              (names.empty() ? std::string("none") : join(names)) +
                              " (describe(false) leaves the training-only geometry head out)");
  }
  s.output = make_port(graph, kExportOutput, "image", graph.outputs.front().second);
  if (s.output.channels != 3)
    throw Error("export", "the output must have 3 channels, the graph's has " + std::to_string(s.output.channels));
  return s;
}

std::string signature_string(const ExportSignature& signature, int64_t width, int64_t height, int64_t batch) {
  std::vector<std::string> ins;
  for (const auto& in : signature.inputs) ins.push_back(in.name + " " + port_shape(in, width, height, batch));
  return join(ins) + " -> " + signature.output.name + " " + port_shape(signature.output, width, height, batch);
}

NamedTensors random_inputs(const ExportSignature& signature, int64_t width, int64_t height, uint64_t seed,
                           int64_t batch) {
  auto generator = at::detail::createCPUGenerator(seed);
  NamedTensors out;
  for (const auto& in : signature.inputs) {
    const int64_t h = height * in.factor, w = width * in.factor;
    if (in.channel_names.empty()) {
      out.emplace_back(in.name, torch::rand({batch, in.channels, h, w}, generator));
      continue;
    }
    out.emplace_back(in.name, random_render_info(in.channel_names, batch, h, w, generator));
  }
  return out;
}

torch::Tensor random_render_info(const std::vector<std::string>& channel_names, int64_t batch, int64_t height,
                                 int64_t width, at::Generator& generator) {
  // Each rendering channel in its own range, so the test data looks like the real thing.
  std::vector<torch::Tensor> parts;
  for (const auto& name : channel_names) {
    const int64_t c = channel_width(channel_from_name(name));
    auto t = torch::rand({batch, c, height, width}, generator);
    if (name == "normal") t = t * 2 - 1;
    if (name == "motion") t = (t - 0.5) * 8;
    if (name == "edge") t = (t > 0.8).to(torch::kFloat);
    parts.push_back(t);
  }
  return torch::cat(parts, 1);
}

std::pair<int64_t, int64_t> check_inputs(const ExportSignature& signature, const NamedTensors& inputs) {
  for (const auto& [name, t] : inputs)
    if (!signature.find_input(name))
      throw Error("input '" + name + "'", "the exported model has no such input");
  const torch::Tensor color = find_tensor(inputs, kExportColorInput);
  if (!color.defined()) throw Error("input '" + std::string(kExportColorInput) + "'", "missing");
  if (color.dim() != 4 || color.size(1) != 3 || color.scalar_type() != torch::kFloat)
    throw Error(kExportColorInput, "expected float32 [N, 3, H, W], got " + shape_string(color));
  const int64_t n = color.size(0), height = color.size(2), width = color.size(3);
  for (const auto& in : signature.inputs) {
    const torch::Tensor t = find_tensor(inputs, in.name);
    if (!t.defined()) throw Error("input '" + in.name + "'", "missing");
    const std::vector<int64_t> want = {n, in.channels, height * in.factor, width * in.factor};
    if (t.sizes().vec() != want || t.scalar_type() != torch::kFloat)
      throw Error(in.name, "expected float32 " + shape_string(torch::empty(want)) + ", got " + shape_string(t));
  }
  return {width, height};
}

torch::Tensor find_tensor(const NamedTensors& tensors, const std::string& name) {
  for (const auto& [n, t] : tensors)
    if (n == name) return t;
  return {};
}

const ExportPort* ExportSignature::info_input() const { return inputs.size() > 1 ? &inputs[1] : nullptr; }

NamedTensors export_inputs(const ExportSignature& signature, const torch::Tensor& lr_color, const torch::Tensor& info) {
  NamedTensors inputs = {{kExportColorInput, lr_color}};
  if (const ExportPort* port = signature.info_input()) inputs.emplace_back(port->name, info);
  return inputs;
}

torch::Tensor info_tensor(const ExportSignature& signature, const NamedTensors& inputs) {
  const ExportPort* port = signature.info_input();
  return port ? find_tensor(inputs, port->name) : torch::Tensor();
}

}  // namespace cgsr
