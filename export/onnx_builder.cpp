#include "export/onnx_builder.h"

#include <torch/torch.h>

#include "core/error.h"
#include "export/onnx_writer.h"

namespace cgsr {

OnnxBuilder::OnnxBuilder(const std::string& graph_name,
                         const std::vector<std::pair<std::string, std::string>>& metadata) {
  model_.set_ir_version(onnx::IR_VERSION);
  model_.set_producer_name("cgsr");
  model_.set_producer_version(CGSR_VERSION);
  model_.set_domain("cgsr");
  auto* opset = model_.add_opset_import();
  opset->set_domain("");
  opset->set_version(kOnnxOpset);
  for (const auto& [key, value] : metadata) {
    auto* prop = model_.add_metadata_props();
    prop->set_key(key);
    prop->set_value(value);
  }
  g_ = model_.mutable_graph();
  g_->set_name(graph_name);
}

void OnnxBuilder::require_opset(int64_t version) {
  for (auto& opset : *model_.mutable_opset_import())
    if (opset.domain().empty() && opset.version() < version) opset.set_version(version);
}

std::string OnnxBuilder::claim(const std::string& name) {
  CGSR_CHECK(used_.insert(name).second, "onnx export: tensor name '" + name + "' used twice");
  return name;
}

void OnnxBuilder::describe(onnx::ValueInfoProto* info, const std::string& name, int elem_type,
                           const std::vector<int64_t>& dims, const std::string& doc,
                           const std::vector<std::string>& symbols) {
  info->set_name(name);
  auto* type = info->mutable_type()->mutable_tensor_type();
  type->set_elem_type(elem_type);
  auto* shape = type->mutable_shape();
  for (size_t i = 0; i < dims.size(); ++i) {
    auto* d = shape->add_dim();
    if (i < symbols.size() && !symbols[i].empty())
      d->set_dim_param(symbols[i]);
    else
      d->set_dim_value(dims[i]);
  }
  if (!doc.empty()) info->set_doc_string(doc);
}

void OnnxBuilder::declare_input(const std::string& name, int elem_type, const std::vector<int64_t>& dims,
                                const std::string& doc, const std::vector<std::string>& symbols) {
  describe(g_->add_input(), name, elem_type, dims, doc, symbols);
}

void OnnxBuilder::declare_output(const std::string& name, int elem_type, const std::vector<int64_t>& dims,
                                 const std::string& doc, const std::vector<std::string>& symbols) {
  describe(g_->add_output(), name, elem_type, dims, doc, symbols);
}

onnx::NodeProto* OnnxBuilder::node(const std::string& type, const std::string& name,
                                   const std::vector<std::string>& inputs, const std::vector<std::string>& outputs) {
  auto* n = g_->add_node();
  n->set_op_type(type);
  n->set_name(name);
  for (const auto& i : inputs) n->add_input(i);
  for (const auto& o : outputs) n->add_output(o);
  return n;
}

void OnnxBuilder::attr(onnx::NodeProto* n, const std::string& name, int64_t v) {
  auto* a = n->add_attribute();
  a->set_name(name);
  a->set_type(onnx::AttributeProto::INT);
  a->set_i(v);
}
void OnnxBuilder::attr(onnx::NodeProto* n, const std::string& name, double v) {
  auto* a = n->add_attribute();
  a->set_name(name);
  a->set_type(onnx::AttributeProto::FLOAT);
  a->set_f(static_cast<float>(v));
}
void OnnxBuilder::attr(onnx::NodeProto* n, const std::string& name, const std::string& v) {
  auto* a = n->add_attribute();
  a->set_name(name);
  a->set_type(onnx::AttributeProto::STRING);
  a->set_s(v);
}
void OnnxBuilder::attr(onnx::NodeProto* n, const std::string& name, const std::vector<int64_t>& v) {
  auto* a = n->add_attribute();
  a->set_name(name);
  a->set_type(onnx::AttributeProto::INTS);
  for (auto x : v) a->add_ints(x);
}

std::string OnnxBuilder::initializer(const std::string& name, const torch::Tensor& value,
                                     const std::vector<int64_t>& shape) {
  const auto t = value.detach().to(torch::kCPU, torch::kFloat).contiguous();
  int64_t count = 1;
  for (auto d : shape) count *= d;
  CGSR_CHECK(t.numel() == count, "onnx export: initializer '" + name + "' has " + std::to_string(t.numel()) +
                                     " values for shape of " + std::to_string(count));
  if (!torch::isfinite(t).all().item<bool>())
    throw Error("onnx export: tensor '" + name + "'", "contains NaN or infinite values");
  auto* init = g_->add_initializer();
  init->set_name(claim(name));
  init->set_data_type(onnx::TensorProto::FLOAT);
  for (auto d : shape) init->add_dims(d);
  init->set_raw_data(t.data_ptr<float>(), static_cast<size_t>(t.numel()) * sizeof(float));
  return name;
}

std::string OnnxBuilder::float_initializer(const std::string& name, const std::vector<float>& values) {
  return initializer(name, torch::tensor(values), {static_cast<int64_t>(values.size())});
}

std::string OnnxBuilder::int64_initializer(const std::string& name, const std::vector<int64_t>& values) {
  auto* init = g_->add_initializer();
  init->set_name(claim(name));
  init->set_data_type(onnx::TensorProto::INT64);
  init->add_dims(static_cast<int64_t>(values.size()));
  for (auto v : values) init->add_int64_data(v);
  return name;
}

std::string OnnxBuilder::int64_scalar(const std::string& name, int64_t value) {
  auto* init = g_->add_initializer();
  init->set_name(claim(name));
  init->set_data_type(onnx::TensorProto::INT64);
  init->add_int64_data(value);
  return name;
}

std::string OnnxBuilder::integer_initializer(const std::string& name, const torch::Tensor& value,
                                             const std::vector<int64_t>& shape) {
  const auto t = value.detach().to(torch::kCPU).contiguous();
  CGSR_CHECK(t.scalar_type() == torch::kChar || t.scalar_type() == torch::kByte || t.scalar_type() == torch::kInt,
             "onnx export: integer initializer '" + name + "' must be int8, uint8 or int32");
  int64_t count = 1;
  for (auto d : shape) count *= d;
  CGSR_CHECK(t.numel() == count, "onnx export: initializer '" + name + "' has the wrong number of values");
  auto* init = g_->add_initializer();
  init->set_name(claim(name));
  init->set_data_type(t.scalar_type() == torch::kChar   ? onnx::TensorProto::INT8
                      : t.scalar_type() == torch::kByte ? onnx::TensorProto::UINT8
                                                        : onnx::TensorProto::INT32);
  for (auto d : shape) init->add_dims(d);
  init->set_raw_data(t.data_ptr(), static_cast<size_t>(t.numel() * t.element_size()));
  return name;
}

std::string OnnxBuilder::serialize(const std::string& context) const {
  std::string bytes;
  CGSR_CHECK(model_.SerializeToString(&bytes), context + ": serialization failed");
  check_onnx_bytes(bytes, context);
  return bytes;
}

}  // namespace cgsr
