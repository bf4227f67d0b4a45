#include "models/precision.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace cgsr {

const std::vector<std::string>& EnumNames<Precision>::names() {
  static const std::vector<std::string> n{"fp32", "bf16", "int8"};
  return n;
}

const std::vector<std::string>& EnumNames<CalibrationMethod>::names() {
  static const std::vector<std::string> n{"max", "percentile"};
  return n;
}

double Calibration::range(const std::string& value) const {
  const auto it = ranges.find(value);
  if (it == ranges.end())
    throw Error("calibration", "no range for value '" + value + "': the calibration was made for another graph");
  return it->second;
}

namespace {

constexpr double kPercentile = 0.9999;
constexpr int64_t kPercentileBins = 1 << 14;

double bound(const torch::Tensor& y, CalibrationMethod method) {
  const torch::Tensor a = y.detach().abs().flatten().to(torch::kFloat);
  const double largest = a.max().item<double>();
  if (method == CalibrationMethod::Max || largest == 0) return largest;
  // From a histogram of |x| over [0, max]: the upper edge of the bin the percentile falls in (a
  // bound within max / 16384 of it). Selecting it exactly (kthvalue, topk) over every element of
  // each HR activation took minutes per network.
  const torch::Tensor cumulative = torch::histc(a, kPercentileBins, 0, largest).to(torch::kDouble).cumsum(0);
  const double k = std::ceil(kPercentile * static_cast<double>(a.numel()));
  const int64_t bin = (cumulative < k).sum().item<int64_t>();
  return largest * static_cast<double>(std::min(bin + 1, kPercentileBins)) / kPercentileBins;
}

}  // namespace

Calibration calibrate(const graph::Graph& graph,
                      const std::vector<std::vector<std::pair<std::string, torch::Tensor>>>& frames,
                      CalibrationMethod method) {
  if (frames.empty()) throw Error("calibration", "no frames to calibrate on");
  torch::NoGradGuard no_grad;
  Calibration c;
  c.method = method;
  for (size_t f = 0; f < frames.size(); ++f) {
    const auto record = [&](const std::string& value, const torch::Tensor& x, const std::string& what) {
      const double b = bound(x, method);
      if (!std::isfinite(b))
        throw Error("calibration", "frame " + std::to_string(f) + ": " + what + " is not finite");
      auto [it, inserted] = c.ranges.emplace(value, b);
      if (!inserted) it->second = std::max(it->second, b);
    };
    // The inputs too: a convolution reading one computes low when told to (FusedGraph::Options::low_convs).
    for (const auto& [name, x] : frames[f])
      if (graph.has_input(name)) record(graph.values[graph.input(name)].name, x, "input '" + name + "'");
    graph::run(graph, frames[f], nullptr, [&](size_t index, const torch::Tensor& y) {
      record(graph.values[graph.ops[index].output].name, y, "op '" + graph.ops[index].name + "' output");
      return y;
    });
  }
  c.frames = static_cast<int64_t>(frames.size());
  return c;
}

std::vector<bool> low_precision_convs(const graph::Graph& graph) {
  const size_t values = graph.values.size(), ops = graph.ops.size();
  std::vector<bool> from_input(values, false), to_output(values, false), low(ops, false);
  for (const auto& [name, v] : graph.inputs) from_input[v] = true;
  for (const auto& op : graph.ops)
    if (op.kind != graph::OpKind::Conv)
      for (int in : op.inputs) from_input[op.output] = from_input[op.output] || from_input[in];
  for (const auto& [name, v] : graph.outputs) to_output[v] = true;
  for (size_t i = ops; i-- > 0;)
    if (graph.ops[i].kind != graph::OpKind::Conv)
      for (int in : graph.ops[i].inputs) to_output[in] = to_output[in] || to_output[graph.ops[i].output];
  for (size_t i = 0; i < ops; ++i) {
    const auto& op = graph.ops[i];
    low[i] = op.kind == graph::OpKind::Conv && !from_input[op.inputs[0]] && !to_output[op.output];
  }
  return low;
}

nlohmann::ordered_json calibration_json(const Calibration& c) {
  nlohmann::ordered_json j;
  j["method"] = enum_name(c.method);
  j["frames"] = c.frames;
  j["ranges"] = nlohmann::ordered_json::object();
  for (const auto& [name, range] : c.ranges) j["ranges"][name] = range;
  return j;
}

Calibration calibration_from_json(const nlohmann::json& j, const std::string& context) {
  try {
    Calibration c;
    c.method = enum_from_name<CalibrationMethod>(j.at("method").get<std::string>());
    c.frames = j.at("frames").get<int64_t>();
    for (const auto& [name, range] : j.at("ranges").items()) {
      const double r = range.get<double>();
      if (!std::isfinite(r) || r < 0) throw Error(context, "calibration range of '" + name + "' is not a finite |x| bound");
      c.ranges[name] = r;
    }
    return c;
  } catch (const nlohmann::json::exception& e) {
    throw Error(context, std::string("malformed calibration: ") + e.what());
  }
}

std::vector<std::pair<std::string, torch::Tensor>> run_fake_int8(
    const graph::Graph& graph, const std::vector<std::pair<std::string, torch::Tensor>>& inputs,
    const Calibration& calibration) {
  const std::vector<bool> low = low_precision_convs(graph);
  graph::Graph g = graph;  // shares the tensors; low convolutions get rounded weights
  std::vector<double> input_steps(g.ops.size(), 0);
  for (size_t i = 0; i < g.ops.size(); ++i) {
    if (!low[i]) continue;
    auto& op = g.ops[i];
    input_steps[i] = int8_scale(calibration.range(g.values[op.inputs[0]].name));
    const torch::Tensor steps = int8_channel_scales(op.weight);
    op.weight = torch::fake_quantize_per_channel_affine(op.weight, steps, torch::zeros_like(steps, torch::kInt), 0,
                                                        -127, 127);
  }
  return graph::run(g, inputs, nullptr, {}, [&](size_t op, const torch::Tensor& x) {
    return low[op] ? torch::fake_quantize_per_tensor_affine(x, input_steps[op], 0, -127, 127) : x;
  });
}

float int8_scale(double range) {
  // A value that was always 0 still gets a positive step (every q is 0 then).
  return static_cast<float>(std::max(range, 1e-12) / 127.0);
}

torch::Tensor quantize_int8(const torch::Tensor& x, float scale) {
  CGSR_CHECK(scale > 0 && std::isfinite(scale), "quantize_int8: the scale must be positive and finite");
  return torch::round(x.to(torch::kFloat) / scale).clamp(-127, 127).to(torch::kChar);
}

torch::Tensor dequantize_int8(const torch::Tensor& q, float scale) { return q.to(torch::kFloat) * scale; }

torch::Tensor int8_channel_scales(const torch::Tensor& weight) {
  const torch::Tensor m = weight.detach().to(torch::kFloat).abs().flatten(1).amax(1);
  return m.clamp_min(1e-12) / 127.0;
}

}  // namespace cgsr
