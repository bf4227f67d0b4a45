#pragma once
// Reduced-precision inference on the fused path (fused_graph.h): the number formats, and the
// activation ranges that INT8 needs (post-training calibration).
//
// INT8 is symmetric: a tensor x is stored as q = round(x / s) saturated to [-127, 127], with one
// scale s per activation tensor (its calibrated range / 127) and one per output channel of a
// convolution's weight (that channel's max |w| / 127). The graph's values are measured in
// float32 on calibration frames (rendered training frames), by the method below.
//
//   Calibration c = calibrate(graph, frames, CalibrationMethod::Percentile);
//   FusedGraph fast(graph, {.precision = Precision::Int8, .calibration = c});

#include <torch/types.h>

#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "core/enum_names.h"
#include "models/graph.h"

namespace cgsr {

enum class Precision {
  Fp32,  // every op in float32
  Bf16,  // convolutions in bfloat16 (float32 accumulation); what stays float32 is the same as INT8's
  Int8,  // convolutions in int8 (int32 accumulation); element-wise work in float32
};
template <>
struct EnumNames<Precision> {
  static constexpr const char* kind = "precision";
  static const std::vector<std::string>& names();  // fp32, bf16, int8
};
// A precision in JSON files is its name ("int8").
template <class J, nlohmann::detail::enable_if_t<nlohmann::detail::is_basic_json<J>::value, int> = 0>
void to_json(J& j, Precision p) {
  j = enum_name(p);
}
template <class J, nlohmann::detail::enable_if_t<nlohmann::detail::is_basic_json<J>::value, int> = 0>
void from_json(const J& j, Precision& p) {
  p = enum_from_name<Precision>(j.template get<std::string>());
}

enum class CalibrationMethod {
  Max,         // the largest |x| seen: nothing saturates, small values get coarse steps
  Percentile,  // the 99.99th percentile of |x| per frame (from a histogram, within max / 16384),
               // the largest over frames: outliers saturate
};
template <>
struct EnumNames<CalibrationMethod> {
  static constexpr const char* kind = "calibration method";
  static const std::vector<std::string>& names();  // max, percentile
};

struct Calibration {
  CalibrationMethod method = CalibrationMethod::Max;
  int64_t frames = 0;                    // how many frames were measured
  std::map<std::string, double> ranges;  // graph value name -> |x| bound, over the frames

  // The value's bound; Error naming the value when it was not calibrated.
  double range(const std::string& value) const;
};

// Which convolutions compute in a reduced precision (indexed like graph.ops; false for other
// ops): all but the wide ones, which read a graph input (colour, depth spanning decades) or write
// a graph output through element-wise ops only, i.e. the first and last layers. The fused path
// and the quantized ONNX export both follow it.
std::vector<bool> low_precision_convs(const graph::Graph& graph);

// How a calibration is recorded in files (model metadata, results): method, frames, ranges.
nlohmann::ordered_json calibration_json(const Calibration& c);
Calibration calibration_from_json(const nlohmann::json& j, const std::string& context);

// Runs `graph` in float32 (graph::run) on every input set in `frames` (each maps the graph's
// input names to tensors, as FusedGraph::run takes them) and records the range of every op's
// output. Deterministic: the same frames give the same ranges. Non-finite activations are an
// Error naming the op and the frame.
Calibration calibrate(const graph::Graph& graph,
                      const std::vector<std::vector<std::pair<std::string, torch::Tensor>>>& frames,
                      CalibrationMethod method);

// INT8 simulated in float32 (fake quantization), for quantization-aware fine-tuning: runs
// `graph` (graph::run) with every low-precision convolution (low_precision_convs) reading its
// input rounded to that value's calibrated step and its weight rounded per output channel, both
// saturated at 127 steps, as the fused INT8 path computes them. Gradients pass the rounding
// unchanged inside the range and are zero outside it (the straight-through estimator), so a
// network trained through it learns weights that survive the rounding. Differentiable when the
// graph's tensors are (subnet_graph with `differentiable`).
std::vector<std::pair<std::string, torch::Tensor>> run_fake_int8(
    const graph::Graph& graph, const std::vector<std::pair<std::string, torch::Tensor>>& inputs,
    const Calibration& calibration);

// The INT8 step for a tensor whose values lie within [-range, range].
float int8_scale(double range);
// round(x / scale) saturated to [-127, 127], as int8; and back (q * scale, float32).
torch::Tensor quantize_int8(const torch::Tensor& x, float scale);
torch::Tensor dequantize_int8(const torch::Tensor& q, float scale);
// Per output channel (dim 0) scales of a convolution weight: max |w| of each channel / 127.
torch::Tensor int8_channel_scales(const torch::Tensor& weight);

}  // namespace cgsr
