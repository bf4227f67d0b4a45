#include "export/onnx_writer.h"

#include <torch/torch.h>

#include <onnx/checker.h>
#include <onnx/defs/schema.h>
#include <onnx/onnx_pb.h>
#include <onnx/shape_inference/implementation.h>

#include <cmath>
#include <set>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/text.h"
#include "export/bicubic_kernel.h"
#include "export/export_signature.h"
#include "export/onnx_builder.h"

namespace cgsr {

const std::vector<std::string>& EnumNames<CubicResize>::names() {
  static const std::vector<std::string> names = {"conv", "native"};
  return names;
}

namespace {

// Builds the GraphProto op by op. Tensor names: graph inputs/outputs by the export signature,
// op outputs by op name, initializers by "<op name>.<role>".
class Writer {
 public:
  Writer(const graph::Graph& graph, const OnnxOptions& options)
      : graph_(graph), options_(options), signature_(export_signature(graph)), b_(options.model_name, options.metadata) {
    if (!options.dynamic_size && (options.width <= 0 || options.height <= 0))
      throw Error("onnx export", "a fixed-size export needs a positive input size, got " +
                                     std::to_string(options.width) + "x" + std::to_string(options.height));
    names_.resize(graph.values.size());
    dequantized_.resize(graph.values.size());
    if (options.int8) int8_convs_ = low_precision_convs(graph);
    for (const auto& op : graph.ops)
      if (op.kind == graph::OpKind::Sample) b_.require_opset(kOnnxGridSampleOpset);
  }

  std::string build() {
    for (const auto& port : signature_.inputs) {
      names_[port.value] = claim(port.name);
      declare(port, /*output=*/false);
    }
    const int output_value = signature_.output.value;
    for (size_t i = 0; i < graph_.ops.size(); ++i) {
      const graph::Op& op = graph_.ops[i];
      // The op producing the graph output writes `sr` directly.
      const std::string out = claim(op.output == output_value ? std::string(kExportOutput) : op.name);
      names_[op.output] = out;
      if (!int8_convs_.empty() && int8_convs_[i])
        emit_int8_conv(op, out);
      else
        emit(op, out);
    }
    if (names_[output_value] != kExportOutput)  // the output is a graph input: nothing computes it
      node("Identity", std::string(kExportOutput) + ".identity", {names_[output_value]}, {claim(kExportOutput)});
    declare(signature_.output, /*output=*/true);
    return b_.serialize("onnx export");
  }

 private:
  static std::string op_context(const std::string& name) { return "onnx export: op '" + name + "'"; }

  // Spatial size of a value at the fixed export size.
  int64_t height_of(int value) const { return options_.height * graph_.values.at(value).factor; }
  int64_t width_of(int value) const { return options_.width * graph_.values.at(value).factor; }

  void declare(const ExportPort& port, bool output) {
    const std::string suffix = port.factor == 1 ? "" : (port.name == kExportOutput ? "_sr" : "_info");
    const std::vector<int64_t> dims = {1, port.channels, options_.height * port.factor, options_.width * port.factor};
    std::vector<std::string> symbols;
    if (options_.dynamic_size) symbols = {"batch", "", "height" + suffix, "width" + suffix};
    std::string doc = port.name == kExportOutput ? "super-resolved RGB, x" + std::to_string(port.factor)
                      : port.name == kExportColorInput ? "low-resolution RGB in [0,1]"
                                                       : "rendering information (" + join(port.channel_names) + ")" +
                                                             (port.factor > 1 ? " at " + std::to_string(port.factor) +
                                                                                    "x the colour size"
                                                                              : " at the colour size");
    if (output)
      b_.declare_output(port.name, onnx::TensorProto::FLOAT, dims, doc, symbols);
    else
      b_.declare_input(port.name, onnx::TensorProto::FLOAT, dims, doc, symbols);
  }

  // The builder's helpers under the names the emitters below use.
  std::string claim(const std::string& name) { return b_.claim(name); }
  onnx::NodeProto* node(const std::string& type, const std::string& name, const std::vector<std::string>& inputs,
                        const std::vector<std::string>& outputs) {
    return b_.node(type, name, inputs, outputs);
  }
  template <typename T>
  static void attr(onnx::NodeProto* n, const std::string& name, const T& v) {
    OnnxBuilder::attr(n, name, v);
  }
  std::string initializer(const std::string& name, const torch::Tensor& value, const std::vector<int64_t>& shape) {
    return b_.initializer(name, value, shape);
  }
  std::string int64_initializer(const std::string& name, const std::vector<int64_t>& values) {
    return b_.int64_initializer(name, values);
  }
  std::string float_initializer(const std::string& name, const std::vector<float>& values) {
    return b_.float_initializer(name, values);
  }

  void emit(const graph::Op& op, const std::string& out) {
    const auto in = [&](size_t i) { return names_.at(op.inputs.at(i)); };
    switch (op.kind) {
      case graph::OpKind::Conv: {
        const auto& w = op.weight;
        if (!w.defined() || w.dim() != 4 || w.size(2) != w.size(3))
          throw Error(op_context(op.name), "conv weight must be [out, in/groups, k, k]");
        std::vector<std::string> inputs = {in(0), initializer(op.name + ".weight", w, w.sizes().vec())};
        if (op.bias.defined()) inputs.push_back(initializer(op.name + ".bias", op.bias, {w.size(0)}));
        conv_attributes(node("Conv", op.name, inputs, {out}), op);
        return;
      }
      case graph::OpKind::Relu: node("Relu", op.name, {in(0)}, {out}); return;
      case graph::OpKind::Sigmoid: node("Sigmoid", op.name, {in(0)}, {out}); return;
      case graph::OpKind::LeakyRelu:
        attr(node("LeakyRelu", op.name, {in(0)}, {out}), "alpha", op.negative_slope);
        return;
      case graph::OpKind::PixelShuffle: {
        auto* n = node("DepthToSpace", op.name, {in(0)}, {out});
        attr(n, "blocksize", op.factor);
        attr(n, "mode", std::string("CRD"));
        return;
      }
      case graph::OpKind::Resize: emit_resize(op, in(0), out); return;
      case graph::OpKind::AvgPool: {
        auto* n = node("AveragePool", op.name, {in(0)}, {out});
        attr(n, "kernel_shape", std::vector<int64_t>{op.factor, op.factor});
        attr(n, "strides", std::vector<int64_t>{op.factor, op.factor});
        return;
      }
      case graph::OpKind::ChannelAffine: {
        const int64_t c = graph::layout_width(graph_.values.at(op.inputs[0]).layout);
        std::string x = in(0);
        if (!op.scale.defined() && !op.shift.defined()) {
          node("Identity", op.name, {x}, {out});
          return;
        }
        if (op.scale.defined()) {
          const std::string y = op.shift.defined() ? claim(op.name + ".scaled") : out;
          node("Mul", op.name + (op.shift.defined() ? ".mul" : ""), {x, initializer(op.name + ".scale", op.scale, {1, c, 1, 1})},
               {y});
          x = y;
        }
        if (op.shift.defined())
          node("Add", op.name + (op.scale.defined() ? ".add" : ""), {x, initializer(op.name + ".shift", op.shift, {1, c, 1, 1})},
               {out});
        return;
      }
      case graph::OpKind::Add: node("Add", op.name, {in(0), in(1)}, {out}); return;
      case graph::OpKind::Mul: node("Mul", op.name, {in(0), in(1)}, {out}); return;
      case graph::OpKind::Concat: {
        std::vector<std::string> inputs;
        for (size_t i = 0; i < op.inputs.size(); ++i) inputs.push_back(in(i));
        attr(node("Concat", op.name, inputs, {out}), "axis", int64_t{1});
        return;
      }
      case graph::OpKind::Sample: emit_sample(op, in(0), in(1), out); return;
      case graph::OpKind::AnyAbsAbove: {
        const std::string magnitude = claim(op.name + ".abs"), largest = claim(op.name + ".max"),
                          above = claim(op.name + ".above");
        node("Abs", op.name + ".abs", {in(0)}, {magnitude});
        auto* reduce = node("ReduceMax", op.name + ".max", {magnitude}, {largest});
        attr(reduce, "axes", std::vector<int64_t>{1});
        attr(reduce, "keepdims", int64_t{1});
        node("Greater", op.name + ".greater",
             {largest, initializer(op.name + ".threshold", torch::tensor(static_cast<float>(op.threshold)), {})},
             {above});
        attr(node("Cast", op.name, {above}, {out}), "to", int64_t{onnx::TensorProto::FLOAT});
        return;
      }
    }
    throw Error(op_context(op.name), std::string("the ONNX writer does not know op kind '") +
                                         graph::op_kind_name(op.kind) + "'");
  }

  static void conv_attributes(onnx::NodeProto* n, const graph::Op& op) {
    attr(n, "kernel_shape", std::vector<int64_t>{op.weight.size(2), op.weight.size(3)});
    attr(n, "pads", std::vector<int64_t>{op.padding, op.padding, op.padding, op.padding});
    attr(n, "strides", std::vector<int64_t>{op.stride, op.stride});
    attr(n, "dilations", std::vector<int64_t>{op.dilation, op.dilation});
    attr(n, "group", op.groups);
  }

  // `value` through QuantizeLinear and DequantizeLinear with the step of its calibrated range,
  // once per value; returns the dequantized tensor's name.
  std::string dequantized(int value) {
    if (!dequantized_[value].empty()) return dequantized_[value];
    const std::string& x = names_.at(value);
    const float step = int8_scale(options_.int8->range(graph_.values[value].name));
    dequantized_[value] = quantize_dequantize(x, x, step);
    return dequantized_[value];
  }

  std::string quantize_dequantize(const std::string& base, const std::string& x, float step,
                                  const std::string& out = "") {
    // uint8 with zero point 128 holds the same symmetric values as int8 (q + 128), and is what
    // ONNX Runtime's x86 int8 kernels take for activations.
    const std::string scale = initializer(base + ".int8_step", torch::tensor(step), {});
    const std::string zero = b_.integer_initializer(base + ".int8_zero", torch::full({}, 128, torch::kByte), {});
    const std::string q = claim(base + ".int8");
    node("QuantizeLinear", base + ".quantize", {x, scale, zero}, {q});
    const std::string y = out.empty() ? claim(base + ".dequantized") : out;
    node("DequantizeLinear", base + ".dequantize", {q, scale, zero}, {y});
    return y;
  }

  // A convolution in INT8 (OnnxOptions::int8), with the fused path's steps (precision.h): the
  // input's calibrated step, per-channel weight steps, the bias in int32 units of their product.
  void emit_int8_conv(const graph::Op& op, const std::string& out) {
    const auto& w = op.weight;
    if (op.groups != 1 || w.size(2) != w.size(3))
      throw Error(op_context(op.name), "int8 export writes square convolutions without groups");
    const float input_step = int8_scale(options_.int8->range(graph_.values[op.inputs[0]].name));
    const std::string x = dequantized(op.inputs[0]);
    const int64_t oc = w.size(0);
    const torch::Tensor steps = int8_channel_scales(w);
    const torch::Tensor wq = torch::round(w / steps.view({oc, 1, 1, 1})).clamp(-127, 127).to(torch::kChar);
    const auto per_channel = [&](const std::string& role, const torch::Tensor& q, const torch::Tensor& s) {
      const std::string name = claim(op.name + "." + role);
      auto* n = node("DequantizeLinear", op.name + "." + role + ".dequantize",
                     {b_.integer_initializer(op.name + "." + role + "_int", q, q.sizes().vec()),
                      initializer(op.name + "." + role + "_step", s, {oc}),
                      b_.integer_initializer(op.name + "." + role + "_zero", torch::zeros({oc}, q.scalar_type()), {oc})},
                     {name});
      attr(n, "axis", int64_t{0});
      return name;
    };
    std::vector<std::string> inputs = {x, per_channel("weight", wq, steps)};
    if (op.bias.defined()) {
      const torch::Tensor bias_steps = steps * input_step;
      const torch::Tensor bq = torch::round(op.bias.to(torch::kFloat) / bias_steps).to(torch::kInt);
      inputs.push_back(per_channel("bias", bq, bias_steps));
    }
    const std::string y = claim(op.name + ".float");
    conv_attributes(node("Conv", op.name, inputs, {y}), op);
    quantize_dequantize(op.name + ".out", y, int8_scale(options_.int8->range(graph_.values[op.output].name)), out);
  }

  void emit_resize(const graph::Op& op, const std::string& x, const std::string& out) {
    if (op.factor < 1) throw Error(op_context(op.name), "resize factor must be >= 1");
    if (op.mode == graph::ResizeMode::Bicubic && options_.cubic == CubicResize::Conv) {
      emit_cubic_as_conv(op, x, out);
      return;
    }
    const float f = static_cast<float>(op.factor);
    const std::string scales = float_initializer(op.name + ".scales", {1.f, 1.f, f, f});
    auto* n = node("Resize", op.name, {x, "", scales}, {out});
    attr(n, "coordinate_transformation_mode", std::string("half_pixel"));
    switch (op.mode) {
      case graph::ResizeMode::Nearest:
        // Source coordinate (j + 0.5) / f - 0.5 rounded half down = j div f: pixel replication.
        attr(n, "mode", std::string("nearest"));
        attr(n, "nearest_mode", std::string("round_prefer_floor"));
        return;
      case graph::ResizeMode::Bilinear: attr(n, "mode", std::string("linear")); return;
      case graph::ResizeMode::Bicubic:
        attr(n, "mode", std::string("cubic"));
        attr(n, "cubic_coeff_a", kBicubicA);
        attr(n, "exclude_outside", int64_t{0});
        return;
    }
    throw Error(op_context(op.name), std::string("unknown resize mode ") + graph::resize_mode_name(op.mode));
  }

  // GridSample over the grid graph::apply_sample computes, with the same float32 operations
  // (graph.h sample_grid_base, sample_grid_scale), built from the tensors' shapes so fixed and
  // dynamic-size files share it: per axis, (float(range(out)) * 2 + 1) / r / float(source) - 1,
  // stacked to [1, H, W, 2]; the offsets transposed to [N, H, W, 2], times 2 / source, plus that.
  void emit_sample(const graph::Op& op, const std::string& source, const std::string& offsets, const std::string& out) {
    const std::string& p = op.name;
    const auto make = [&](const std::string& type, const std::string& role, const std::vector<std::string>& inputs) {
      const std::string y = claim(p + "." + role);
      node(type, p + "." + role, inputs, {y});
      return y;
    };
    const auto to_float = [&](const std::string& role, const std::string& x) {
      const std::string y = claim(p + "." + role);
      attr(node("Cast", p + "." + role, {x}, {y}), "to", int64_t{onnx::TensorProto::FLOAT});
      return y;
    };
    const auto axes = [&](const std::string& role, int64_t axis) { return int64_initializer(p + "." + role, {axis}); };
    const auto concat = [&](const std::string& role, const std::vector<std::string>& parts, int64_t axis) {
      const std::string y = claim(p + "." + role);
      attr(node("Concat", p + "." + role, parts, {y}), "axis", axis);
      return y;
    };
    const std::string source_shape = make("Shape", "source_shape", {source});
    const std::string offsets_shape = make("Shape", "offsets_shape", {offsets});
    const std::string two = initializer(p + ".two", torch::tensor(2.f), {});
    const std::string one = initializer(p + ".one", torch::tensor(1.f), {});
    const std::string ratio = initializer(p + ".ratio", torch::tensor(static_cast<float>(op.factor)), {});
    const std::string start = b_.int64_scalar(p + ".range_start", 0), step = b_.int64_scalar(p + ".range_step", 1);
    // Normalized centres along one axis (dim 3: x, dim 2: y) and 2 / the source's size.
    const auto axis = [&](const std::string& a, int64_t dim) {
      const std::string index = b_.int64_scalar(p + "." + a + "_dim", dim);
      const std::string size = to_float(a + "_source_size", make("Gather", a + "_source_dim", {source_shape, index}));
      const std::string count = make("Gather", a + "_out_dim", {offsets_shape, index});
      const std::string ramp = to_float(a + "_ramp", make("Range", a + "_range", {start, count, step}));
      const std::string odd = make("Add", a + "_odd", {make("Mul", a + "_twice", {ramp, two}), one});
      const std::string lr = make("Div", a + "_lr", {odd, ratio});
      const std::string centres = make("Sub", a + "_centres", {make("Div", a + "_normalized", {lr, size}), one});
      return std::make_pair(centres, make("Div", a + "_scale", {two, size}));
    };
    const auto [x_centres, x_scale] = axis("x", 3);
    const auto [y_centres, y_scale] = axis("y", 2);
    const std::string out_hw = make("Slice", "out_hw", {offsets_shape, int64_initializer(p + ".hw_start", {2}),
                                                         int64_initializer(p + ".hw_end", {4})});
    const std::string x_grid = make("Expand", "x_grid", {make("Unsqueeze", "x_row", {x_centres, axes("row_axes", 0)}), out_hw});
    const std::string y_grid = make("Expand", "y_grid", {make("Unsqueeze", "y_column", {y_centres, axes("column_axes", 1)}), out_hw});
    const std::string last = axes("last_axes", 2);
    const std::string stacked = concat("stacked", {make("Unsqueeze", "x_last", {x_grid, last}), make("Unsqueeze", "y_last", {y_grid, last})}, 2);
    const std::string base = make("Unsqueeze", "grid_base", {stacked, axes("batch_axes", 0)});
    const std::string first = axes("scale_axes", 0);
    const std::string scale = concat("grid_scale", {make("Unsqueeze", "x_scale1", {x_scale, first}),
                                                    make("Unsqueeze", "y_scale1", {y_scale, first})}, 0);
    const std::string transposed = claim(p + ".offsets_nhwc");
    attr(node("Transpose", p + ".transpose", {offsets}, {transposed}), "perm", std::vector<int64_t>{0, 2, 3, 1});
    const std::string grid = make("Add", "grid", {make("Mul", "scaled", {transposed, scale}), base});
    auto* n = node("GridSample", op.name, {source, grid}, {out});
    attr(n, "mode", std::string(graph::resize_mode_name(op.mode)));  // opset 16: nearest, bilinear, bicubic
    attr(n, "padding_mode", std::string("border"));
    attr(n, "align_corners", int64_t{0});
  }

  // Bicubic upsampling as edge padding + a depthwise conv computing the f*f phases + DepthToSpace
  // (bicubic_kernel.h). Exact up to float rounding, and runs wherever Conv and DepthToSpace run.
  void emit_cubic_as_conv(const graph::Op& op, const std::string& x, const std::string& out) {
    const int64_t c = graph::layout_width(graph_.values.at(op.inputs[0]).layout), f = op.factor;
    const int64_t r = kBicubicPhaseRadius;
    const std::string padded = claim(op.name + ".padded");
    auto* pad = node("Pad", op.name + ".pad", {x, int64_initializer(op.name + ".pads", {0, 0, r, r, 0, 0, r, r})},
                     {padded});
    attr(pad, "mode", std::string("edge"));
    const torch::Tensor kernel = bicubic_phase_kernels(f).repeat({c, 1, 1, 1});  // [c*f*f, 1, 5, 5]
    const std::string phases = claim(op.name + ".phases");
    auto* conv = node("Conv", op.name + ".conv", {padded, initializer(op.name + ".kernel", kernel, kernel.sizes().vec())},
                      {phases});
    attr(conv, "kernel_shape", std::vector<int64_t>{kernel.size(2), kernel.size(3)});
    attr(conv, "pads", std::vector<int64_t>{0, 0, 0, 0});
    attr(conv, "group", c);
    auto* d2s = node("DepthToSpace", op.name, {phases}, {out});
    attr(d2s, "blocksize", f);
    attr(d2s, "mode", std::string("CRD"));
  }

  const graph::Graph& graph_;
  const OnnxOptions& options_;
  ExportSignature signature_;
  OnnxBuilder b_;
  std::vector<std::string> names_;
  std::vector<std::string> dequantized_;  // per value: its QuantizeLinear/DequantizeLinear output, once made
  std::vector<bool> int8_convs_;          // per op: written in INT8 (empty: float32 export)
};

onnx::ModelProto parse_model(const std::string& bytes, const std::string& context) {
  onnx::ModelProto model;
  if (bytes.empty()) throw Error(context, "empty file, not an ONNX model");
  if (!model.ParseFromString(bytes)) throw Error(context, "not an ONNX model (the protobuf does not parse)");
  return model;
}

void check_model(const onnx::ModelProto& model, const std::string& context) {
  try {
    onnx::checker::check_model(model);
  } catch (const std::exception& e) {
    throw Error(context, std::string("ONNX checker: ") + e.what());
  }
  try {
    onnx::ModelProto copy = model;
    onnx::ShapeInferenceOptions strict(/*check_type_val=*/true, /*strict_mode_val=*/1, /*data_prop_val=*/false);
    onnx::shape_inference::InferShapes(copy, onnx::OpSchemaRegistry::Instance(), strict);
  } catch (const std::exception& e) {
    throw Error(context, std::string("ONNX shape inference: ") + e.what());
  }
}

OnnxTensorInfo tensor_info(const onnx::ValueInfoProto& v) {
  OnnxTensorInfo info;
  info.name = v.name();
  for (const auto& d : v.type().tensor_type().shape().dim()) {
    OnnxDim dim;
    if (d.has_dim_value()) dim.value = d.dim_value();
    else dim.param = d.dim_param();
    info.dims.push_back(dim);
  }
  return info;
}

}  // namespace

std::string onnx_model_bytes(const graph::Graph& graph, const OnnxOptions& options) {
  return Writer(graph, options).build();
}

void write_onnx(const std::filesystem::path& path, const graph::Graph& graph, const OnnxOptions& options) {
  write_file_atomic(path, onnx_model_bytes(graph, options));
  check_onnx_file(path);
}

void check_onnx_bytes(const std::string& bytes, const std::string& context) {
  check_model(parse_model(bytes, context), context);
}

void check_onnx_file(const std::filesystem::path& path) { check_onnx_bytes(read_file(path), path.string()); }

bool OnnxModelInfo::dynamic() const {
  for (const auto& in : inputs)
    for (const auto& d : in.dims)
      if (d.value < 0) return true;
  return false;
}

const OnnxTensorInfo* OnnxModelInfo::find_input(const std::string& name) const {
  for (const auto& in : inputs)
    if (in.name == name) return &in;
  return nullptr;
}

std::string OnnxModelInfo::metadata_value(const std::string& key) const {
  for (const auto& [k, v] : metadata)
    if (k == key) return v;
  return "";
}

OnnxModelInfo inspect_onnx_file(const std::filesystem::path& path) {
  const std::string context = path.string();
  const onnx::ModelProto model = parse_model(read_file(path), context);
  check_model(model, context);
  OnnxModelInfo info;
  for (const auto& opset : model.opset_import())
    if (opset.domain().empty() || opset.domain() == "ai.onnx") info.opset = opset.version();
  std::set<std::string> initializers;
  for (const auto& init : model.graph().initializer()) initializers.insert(init.name());
  for (const auto& in : model.graph().input())
    if (!initializers.count(in.name())) info.inputs.push_back(tensor_info(in));
  for (const auto& out : model.graph().output()) info.outputs.push_back(tensor_info(out));
  for (const auto& n : model.graph().node()) {
    bool found = false;
    for (auto& [type, count] : info.op_counts)
      if (type == n.op_type()) {
        ++count;
        found = true;
      }
    if (!found) info.op_counts.emplace_back(n.op_type(), 1);
  }
  for (const auto& p : model.metadata_props()) info.metadata.emplace_back(p.key(), p.value());
  return info;
}

}  // namespace cgsr
