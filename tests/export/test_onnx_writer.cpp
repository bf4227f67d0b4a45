// The ONNX writer: what the files hold (ops, attributes, interface), the checker on every file,
// and clear errors for what it cannot write or read.

#include <gtest/gtest.h>

#include <torch/torch.h>

#include <onnx/onnx_pb.h>

#include <fstream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "export/exporter.h"
#include "export/onnx_writer.h"
#include "tests/export/export_cases.h"
#include "tests/support/cli_runner.h"

namespace cgsr {
namespace {

onnx::ModelProto model_of(const graph::Graph& g, const OnnxOptions& o) {
  onnx::ModelProto m;
  EXPECT_TRUE(m.ParseFromString(onnx_model_bytes(g, o)));
  return m;
}

OnnxOptions fixed(int64_t w, int64_t h) {
  OnnxOptions o;
  o.width = w;
  o.height = h;
  return o;
}

std::vector<const onnx::NodeProto*> nodes_of(const onnx::ModelProto& m, const std::string& type) {
  std::vector<const onnx::NodeProto*> out;
  for (const auto& n : m.graph().node())
    if (n.op_type() == type) out.push_back(&n);
  return out;
}

const onnx::AttributeProto* attribute(const onnx::NodeProto& n, const std::string& name) {
  for (const auto& a : n.attribute())
    if (a.name() == name) return &a;
  return nullptr;
}

const onnx::TensorProto* initializer(const onnx::ModelProto& m, const std::string& name) {
  for (const auto& t : m.graph().initializer())
    if (t.name() == name) return &t;
  return nullptr;
}

std::vector<int64_t> dims(const onnx::TensorProto& t) { return {t.dims().begin(), t.dims().end()}; }

std::vector<std::string> shape(const onnx::ValueInfoProto& v) {
  std::vector<std::string> out;
  for (const auto& d : v.type().tensor_type().shape().dim())
    out.push_back(d.has_dim_value() ? std::to_string(d.dim_value()) : d.dim_param());
  return out;
}

TEST(OnnxWriter, EdsrConvsCarryKernelShapesAndPixelShuffleIsDepthToSpaceCrd) {
  SRNetwork net = test::build_network(test::shrunk_edsr(4), 1);
  const graph::Graph g = net->describe();
  const auto m = model_of(g, fixed(12, 10));
  ASSERT_EQ(m.opset_import_size(), 1);
  EXPECT_EQ(m.opset_import(0).version(), 13);
  size_t convs = 0;
  for (const auto& op : g.ops) convs += op.kind == graph::OpKind::Conv;
  ASSERT_EQ(nodes_of(m, "Conv").size(), convs);
  for (const auto* n : nodes_of(m, "Conv")) {
    const auto* k = attribute(*n, "kernel_shape");
    ASSERT_NE(k, nullptr) << n->name();
    const auto* w = initializer(m, n->input(1));
    ASSERT_NE(w, nullptr) << n->name();
    EXPECT_EQ(std::vector<int64_t>(k->ints().begin(), k->ints().end()), (std::vector<int64_t>{dims(*w)[2], dims(*w)[3]}));
    EXPECT_EQ(g.find_op(n->name())->weight.sizes().vec(), dims(*w));
  }
  const auto d2s = nodes_of(m, "DepthToSpace");
  ASSERT_EQ(d2s.size(), 2u);  // x4 = two x2 stages
  for (const auto* n : d2s) {
    EXPECT_EQ(attribute(*n, "mode")->s(), "CRD");
    EXPECT_EQ(attribute(*n, "blocksize")->i(), 2);
  }
  // The mean shift is a fixed 1x1 conv whose bias is the mean.
  const auto* mean = initializer(m, "backbone.add_mean.bias");
  ASSERT_NE(mean, nullptr);
  EXPECT_EQ(dims(*mean), (std::vector<int64_t>{3}));
  ASSERT_EQ(m.graph().input_size(), 1);
  EXPECT_EQ(m.graph().input(0).name(), "lr_color");
  EXPECT_EQ(shape(m.graph().input(0)), (std::vector<std::string>{"1", "3", "10", "12"}));
  EXPECT_EQ(m.graph().output(0).name(), "sr");
  EXPECT_EQ(shape(m.graph().output(0)), (std::vector<std::string>{"1", "3", "40", "48"}));
}

TEST(OnnxWriter, PanResizesUseHalfPixelCentres) {
  SRNetwork net = test::build_network(test::shrunk_pan(3), 2);
  const auto m = model_of(net->describe(), fixed(12, 10));
  const auto resizes = nodes_of(m, "Resize");
  ASSERT_EQ(resizes.size(), 2u);  // nearest before upconv1, bilinear skip
  std::set<std::string> modes;
  for (const auto* n : resizes) {
    EXPECT_EQ(attribute(*n, "coordinate_transformation_mode")->s(), "half_pixel");
    const std::string mode = attribute(*n, "mode")->s();
    modes.insert(mode);
    if (mode == "nearest") {
      EXPECT_EQ(attribute(*n, "nearest_mode")->s(), "round_prefer_floor");
    }
    const auto* scales = initializer(m, n->input(2));
    ASSERT_NE(scales, nullptr);
    EXPECT_EQ(scales->raw_data().size(), 4 * sizeof(float));
    const float* s = reinterpret_cast<const float*>(scales->raw_data().data());
    EXPECT_EQ(std::vector<float>(s, s + 4), (std::vector<float>{1, 1, 3, 3}));
  }
  EXPECT_EQ(modes, (std::set<std::string>{"nearest", "linear"}));
  EXPECT_EQ(nodes_of(m, "Sigmoid").size(), 2u + 1);  // the PA conv attention of each block, att1
  EXPECT_FALSE(nodes_of(m, "Mul").empty());
}

TEST(OnnxWriter, BicubicIsAPortableConvByDefaultOrANativeCubicResize) {
  SRNetwork net = test::build_network(test::spec_for({"srcnn", 3, "y"}), 3);
  const graph::Graph g = net->describe();
  const auto as_conv = model_of(g, fixed(12, 10));
  EXPECT_TRUE(nodes_of(as_conv, "Resize").empty());
  ASSERT_EQ(nodes_of(as_conv, "Pad").size(), 1u);
  EXPECT_EQ(attribute(*nodes_of(as_conv, "Pad")[0], "mode")->s(), "edge");
  // SRCNN's Y mode: its fixed colour convs are plain convs in the file, as the graph says.
  ASSERT_NE(initializer(as_conv, "backbone.to_y.weight"), nullptr);
  EXPECT_EQ(dims(*initializer(as_conv, "backbone.to_y.weight")), (std::vector<int64_t>{1, 3, 1, 1}));
  ASSERT_NE(initializer(as_conv, "backbone.merge_y.weight"), nullptr);

  OnnxOptions o = fixed(12, 10);
  o.cubic = CubicResize::Native;
  const auto native = model_of(g, o);
  ASSERT_EQ(nodes_of(native, "Resize").size(), 1u);
  const auto& r = *nodes_of(native, "Resize")[0];
  EXPECT_EQ(attribute(r, "mode")->s(), "cubic");
  EXPECT_FLOAT_EQ(attribute(r, "cubic_coeff_a")->f(), -0.75f);
  EXPECT_EQ(attribute(r, "exclude_outside")->i(), 0);
  EXPECT_EQ(attribute(r, "coordinate_transformation_mode")->s(), "half_pixel");
  EXPECT_TRUE(nodes_of(native, "Pad").empty());
}

TEST(OnnxWriter, RenderInfoInputHasOnlyTheModelsChannelsAtItsResolution) {
  ArchSpec spec = test::with_rit(default_spec("pan", 2), "hr_pooled", "add");
  spec.rit.channels = {"depth", "edge"};
  spec = resolve_spec(spec);
  SRNetwork net = test::build_network(spec, 4);
  const auto m = model_of(net->describe(), fixed(12, 10));
  ASSERT_EQ(m.graph().input_size(), 2);
  EXPECT_EQ(m.graph().input(1).name(), "hr_render_info");
  EXPECT_EQ(shape(m.graph().input(1)), (std::vector<std::string>{"1", "2", "20", "24"}));
  EXPECT_EQ(nodes_of(m, "AveragePool").size(), 1u);
  // The RIT gate (a channel affine) is a Mul by a [1, C, 1, 1] initializer.
  const auto* gate = initializer(m, "rit.gate.scale");
  ASSERT_NE(gate, nullptr);
  EXPECT_EQ(dims(*gate), (std::vector<int64_t>{1, 2, 1, 1}));

  OnnxOptions o;
  o.dynamic_size = true;
  const auto d = model_of(net->describe(), o);
  EXPECT_EQ(shape(d.graph().input(0)), (std::vector<std::string>{"batch", "3", "height", "width"}));
  EXPECT_EQ(shape(d.graph().input(1)), (std::vector<std::string>{"batch", "2", "height_info", "width_info"}));
  EXPECT_EQ(shape(d.graph().output(0)), (std::vector<std::string>{"batch", "3", "height_sr", "width_sr"}));
  // The geometry head is never exported: a model without RIT has no info input at all.
  SRNetwork plain = test::build_network(default_spec("pan", 2), 5);
  EXPECT_EQ(model_of(plain->describe(), fixed(4, 4)).graph().input_size(), 1);
}

TEST(OnnxWriter, WrittenFilesPassTheCheckerAndRecordTheSpec) {
  const auto dir = test::scratch_dir("onnx-writer");
  SRNetwork net = test::build_network(test::with_rit(test::shrunk_pan(2)), 6);
  ExportOptions o;
  o.width = 8;
  o.height = 6;
  const auto m = export_network(*net, dir / "pan.onnx", o);
  EXPECT_NO_THROW(check_onnx_file(m.file));
  const OnnxModelInfo info = inspect_onnx_file(m.file);
  EXPECT_EQ(info.opset, 13);
  EXPECT_FALSE(info.dynamic());
  EXPECT_EQ(info.metadata_value("cgsr.scale"), "2");
  EXPECT_EQ(spec_from_yaml(info.metadata_value("cgsr.spec"), "metadata"), net->spec());
  EXPECT_EQ(info.metadata_value("cgsr.render_channels"), "depth, normal, normal_angle, edge");
  // No temporary file is left next to the output.
  for (const auto& e : std::filesystem::directory_iterator(dir))
    EXPECT_EQ(e.path().filename(), "pan.onnx");
  std::filesystem::remove_all(dir);
}

TEST(OnnxWriter, CorruptFilesAreClearErrors) {
  const auto dir = test::scratch_dir("onnx-corrupt");
  SRNetwork net = test::build_network(test::shrunk_edsr(2), 7);
  const std::string good = onnx_model_bytes(net->describe(), fixed(6, 5));
  const auto expect_error = [&](const std::string& bytes, const std::string& fragment) {
    const auto file = dir / "bad.onnx";
    write_file_atomic(file, bytes);
    try {
      check_onnx_file(file);
      ADD_FAILURE() << "no error for " << fragment;
    } catch (const Error& e) {
      EXPECT_EQ(e.context(), file.string());
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  };
  expect_error("", "empty file");
  expect_error("this is not a protobuf at all", "not an ONNX model");
  expect_error(good.substr(0, good.size() / 2), "not an ONNX model");  // truncated
  // Well-formed protobuf, broken model: a conv whose weight is gone.
  onnx::ModelProto m;
  ASSERT_TRUE(m.ParseFromString(good));
  auto* inits = m.mutable_graph()->mutable_initializer();
  for (int i = 0; i < inits->size(); ++i)
    if (inits->Get(i).name() == "backbone.head.weight") inits->DeleteSubrange(i, 1);
  std::string broken;
  ASSERT_TRUE(m.SerializeToString(&broken));
  expect_error(broken, "backbone.head.weight");
  // A node the ONNX schema does not know.
  ASSERT_TRUE(m.ParseFromString(good));
  m.mutable_graph()->mutable_node(0)->set_op_type("NoSuchOp");
  ASSERT_TRUE(m.SerializeToString(&broken));
  expect_error(broken, "ONNX checker");
  std::filesystem::remove_all(dir);
}

TEST(OnnxWriter, WhatTheWriterCannotExpressIsAClearError) {
  SRNetwork net = test::build_network(test::shrunk_edsr(2), 8);
  graph::Graph g = net->describe();
  // An op kind the writer does not know.
  graph::Graph unknown = g;
  unknown.ops[1].kind = static_cast<graph::OpKind>(99);
  try {
    onnx_model_bytes(unknown, fixed(6, 5));
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(unknown.ops[1].name), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("does not know"), std::string::npos) << e.what();
  }
  // A training graph: the geometry head is not part of an export.
  SRNetwork with_head = test::build_network(test::with_rit(default_spec("srcnn", 2), "lr", "add", true), 9);
  EXPECT_THROW(onnx_model_bytes(with_head->describe(/*training=*/true), fixed(6, 5)), Error);
  EXPECT_NO_THROW(onnx_model_bytes(with_head->describe(/*training=*/false), fixed(6, 5)));
  // A fixed-size export without a size, weights that are not finite.
  EXPECT_THROW(onnx_model_bytes(g, OnnxOptions()), Error);
  graph::Graph nan = g;
  nan.ops[1].weight = nan.ops[1].weight.clone();
  nan.ops[1].weight.view(-1)[0] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(onnx_model_bytes(nan, fixed(6, 5)), Error);
  EXPECT_THROW(enum_from_name<CubicResize>("cubic"), Error);
}

}  // namespace
}  // namespace cgsr
