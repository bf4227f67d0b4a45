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

double bound(const torch::Tensor& y, CalibrationMethod method) {
  const torch::Tensor a = y.detach().abs().flatten().to(torch::kDouble);
  if (method == CalibrationMethod::Max || a.numel() < 2) return a.max().item<double>();
  const int64_t k = std::clamp<int64_t>(static_cast<int64_t>(std::ceil(kPercentile * a.numel())), 1, a.numel());
  return std::get<0>(a.kthvalue(k)).item<double>();
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
    graph::run(graph, frames[f], nullptr, [&](size_t index, const torch::Tensor& y) {
      const std::string& name = graph.values[graph.ops[index].output].name;
      const double b = bound(y, method);
      if (!std::isfinite(b))
        throw Error("calibration", "frame " + std::to_string(f) + ": op '" + graph.ops[index].name +
                                       "' produced a non-finite value");
      auto [it, inserted] = c.ranges.emplace(name, b);
      if (!inserted) it->second = std::max(it->second, b);
      return y;
    });
  }
  c.frames = static_cast<int64_t>(frames.size());
  return c;
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
