#pragma once
// Building an ONNX model with libonnx's protobuf classes: the model header (IR version,
// producer, opset kOnnxOpset, metadata_props), nodes, attributes and initializers, with every
// tensor name claimed once. The network writer (onnx_writer.cpp) and the hybrid selector
// (selector_onnx.cpp) both build through it.
//
//   OnnxBuilder b("selector", metadata);
//   b.declare_input("x", onnx::TensorProto::FLOAT, {1, 3, 4, 4}, "doc");
//   b.attr(b.node("Relu", "relu", {"x"}, {b.claim("y")}), ...);
//   b.declare_output("y", onnx::TensorProto::FLOAT, {1, 3, 4, 4}, "doc");
//   std::string bytes = b.serialize("selector export");   // checked with check_onnx_bytes

#include <torch/types.h>

#include <onnx/onnx_pb.h>

#include <cstdint>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace cgsr {

class OnnxBuilder {
 public:
  OnnxBuilder(const std::string& graph_name, const std::vector<std::pair<std::string, std::string>>& metadata);

  onnx::GraphProto& graph() { return *g_; }

  // Raises the default domain's opset to at least `version` (kOnnxOpset unless an op needs more).
  void require_opset(int64_t version);

  // Reserves a tensor name; a name used twice is an internal error.
  std::string claim(const std::string& name);

  // A graph input/output of `elem_type` (onnx::TensorProto::FLOAT, INT64, ...): dim i is the
  // symbol symbols[i] when that is given and not empty, else the number dims[i].
  void declare_input(const std::string& name, int elem_type, const std::vector<int64_t>& dims,
                     const std::string& doc, const std::vector<std::string>& symbols = {});
  void declare_output(const std::string& name, int elem_type, const std::vector<int64_t>& dims,
                      const std::string& doc, const std::vector<std::string>& symbols = {});

  // Adds a node (outputs must already be claimed or be graph outputs claimed by the caller).
  onnx::NodeProto* node(const std::string& type, const std::string& name, const std::vector<std::string>& inputs,
                        const std::vector<std::string>& outputs);

  static void attr(onnx::NodeProto* n, const std::string& name, int64_t v);
  static void attr(onnx::NodeProto* n, const std::string& name, double v);
  static void attr(onnx::NodeProto* n, const std::string& name, const std::string& v);
  static void attr(onnx::NodeProto* n, const std::string& name, const std::vector<int64_t>& v);

  // Float initializer of `shape` from a tensor (any dtype, copied as float32); NaN or infinite
  // values are an error naming the tensor. Returns the name.
  std::string initializer(const std::string& name, const torch::Tensor& value, const std::vector<int64_t>& shape);
  std::string float_initializer(const std::string& name, const std::vector<float>& values);  // 1-D
  std::string int64_initializer(const std::string& name, const std::vector<int64_t>& values);  // 1-D
  std::string int64_scalar(const std::string& name, int64_t value);  // 0-D (Gather indices, Range bounds)
  // INT8, UINT8 or INT32 initializer of `shape` from a kChar, kByte or kInt tensor, as stored.
  std::string integer_initializer(const std::string& name, const torch::Tensor& value, const std::vector<int64_t>& shape);

  // Serialized and checked (check_onnx_bytes); errors name `context`.
  std::string serialize(const std::string& context) const;

 private:
  static void describe(onnx::ValueInfoProto* info, const std::string& name, int elem_type,
                       const std::vector<int64_t>& dims, const std::string& doc,
                       const std::vector<std::string>& symbols);

  onnx::ModelProto model_;
  onnx::GraphProto* g_ = nullptr;
  std::set<std::string> used_;
};

}  // namespace cgsr
