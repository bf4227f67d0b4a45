#pragma once
// Writes a network's inference graph (models/graph.h) as an ONNX model, opset 13, through the
// ONNX protobuf classes of libonnx, and checks every file with the ONNX checker plus strict
// shape inference.
//
// Op mapping (graph op -> ONNX):
//   Conv           Conv with kernel_shape, pads, strides, dilations, group; weights as initializers
//   Relu, Sigmoid  Relu, Sigmoid;  LeakyRelu -> LeakyRelu(alpha)
//   PixelShuffle   DepthToSpace, mode CRD (PyTorch's channel order)
//   Resize         Resize with `scales` [1, 1, f, f], coordinate_transformation_mode half_pixel:
//                  nearest with nearest_mode round_prefer_floor (= pixel replication for integer
//                  factors), linear, or cubic (cubic_coeff_a -0.75, exclude_outside 0). Bicubic can
//                  instead be written as an exact fixed-weight conv (CubicResize::Conv): edge
//                  padding by 2, a depthwise 5x5 conv producing the f*f sub-pixel phases, and
//                  DepthToSpace; OpenCV DNN 4.6 has no cubic Resize, every runtime has Conv.
//   AvgPool        AveragePool, kernel = stride = f
//   ChannelAffine  Mul / Add with [1, C, 1, 1] initializers
//   Add, Mul       Add, Mul;  Concat -> Concat(axis 1)
//
// Inputs `lr_color`, `lr_render_info` or `hr_render_info` and output `sr` as in export_signature.h. With a fixed
// size, every dimension is a number (batch 1); with `dynamic_size`, batch, height and width are
// symbolic (the rendering information of an hr_pooled model has its own symbolic height/width,
// which must be scale x the colour size).

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/enum_names.h"
#include "models/graph.h"
#include "models/precision.h"

namespace cgsr {

enum class CubicResize { Conv, Native };
template <>
struct EnumNames<CubicResize> {
  static constexpr const char* kind = "cubic resize";
  static const std::vector<std::string>& names();  // conv, native
};

struct OnnxOptions {
  int64_t width = 0, height = 0;  // LR input size written into the file; ignored with dynamic_size
  bool dynamic_size = false;
  CubicResize cubic = CubicResize::Conv;
  std::string model_name = "cgsr";                              // graph name
  std::vector<std::pair<std::string, std::string>> metadata;  // metadata_props, e.g. {"cgsr.spec", yaml}
  // INT8 as QDQ: each convolution low_precision_convs() picks reads its input through a
  // QuantizeLinear/DequantizeLinear pair (the calibrated step; uint8 with zero point 128, the same
  // symmetric values), its weight as int8 per output channel and its bias as int32 through
  // DequantizeLinear, and its result passes a pair of its own (the step of its calibrated
  // output), so ONNX Runtime runs it as an int8 convolution. Empty: float32.
  std::optional<Calibration> int8;
};

inline constexpr int64_t kOnnxOpset = 13;
// A graph with a Sample op is written at this opset instead (GridSample first appears in 16), so
// every other export keeps the opset older runtimes import.
inline constexpr int64_t kOnnxGridSampleOpset = 16;

// The serialized ModelProto, already checked. Throws cgsr::Error naming the op for a graph op or
// option the writer cannot express.
std::string onnx_model_bytes(const graph::Graph& graph, const OnnxOptions& options);

// Writes the model atomically, then re-reads and checks the written file.
void write_onnx(const std::filesystem::path& path, const graph::Graph& graph, const OnnxOptions& options);

// ONNX checker (onnx::checker::check_model) and strict shape inference on a serialized model or a
// file; cgsr::Error(context, checker message) on failure.
void check_onnx_bytes(const std::string& bytes, const std::string& context);
void check_onnx_file(const std::filesystem::path& path);

// What a file declares, for runners and benchmarks.
struct OnnxDim {
  int64_t value = -1;  // -1 when symbolic
  std::string param;   // the symbol name when symbolic
};
struct OnnxTensorInfo {
  std::string name;
  std::vector<OnnxDim> dims;
};
struct OnnxModelInfo {
  int64_t opset = 0;
  std::vector<OnnxTensorInfo> inputs, outputs;
  std::vector<std::pair<std::string, int>> op_counts;  // op type -> nodes, in first-seen order
  std::vector<std::pair<std::string, std::string>> metadata;
  bool dynamic() const;  // any symbolic input dimension
  const OnnxTensorInfo* find_input(const std::string& name) const;
  std::string metadata_value(const std::string& key) const;  // "" when absent
};
OnnxModelInfo inspect_onnx_file(const std::filesystem::path& path);  // also checks the file

}  // namespace cgsr
