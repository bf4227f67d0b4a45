// INT8 export: a QDQ ONNX file (QuantizeLinear/DequantizeLinear around the convolutions the fused
// path runs in int8) that records its calibration, and that ONNX Runtime runs in agreement with
// the fused path's int8 output.

#include <gtest/gtest.h>

#include <torch/torch.h>

#include <onnx/onnx_pb.h>

#include <fstream>
#include <set>

#include "core/error.h"
#include "export/exporter.h"
#include "export/onnx_writer.h"
#include "export/verification.h"
#include "models/fused_graph.h"
#include "models/precision.h"
#include "tests/models/numerics_cases.h"
#include "tests/support/cli_runner.h"

namespace cgsr {
namespace int8_export_test {

constexpr int64_t kWidth = 16, kHeight = 12;

// Smooth colour and rendering information in [0, 1], as rendered frames are (noise would put
// every activation outside the calibrated ranges).
std::pair<torch::Tensor, torch::Tensor> smooth_frame(const SRNetworkImpl& net, uint64_t seed) {
  torch::manual_seed(seed);
  const auto smooth = [](int64_t c, int64_t h, int64_t w) {
    return torch::upsample_bilinear2d(torch::rand({1, c, 4, 4}), {h, w}, false);
  };
  torch::Tensor info;
  if (net.has_rit()) {
    const int64_t f = net.rit()->info_factor();
    info = smooth(net.spec().rit.info_width(), kHeight * f, kWidth * f);
  }
  return {smooth(3, kHeight, kWidth), info};
}

struct Int8Export {
  SRNetwork net;
  Calibration calibration;
  ExportedModel exported;
  onnx::ModelProto model;
};

Int8Export export_int8(const ArchSpec& spec, const std::filesystem::path& file) {
  Int8Export e{test::perturbed_network(spec, 31), {}, {}, {}};
  const graph::Graph g = e.net->describe();
  std::vector<std::vector<std::pair<std::string, torch::Tensor>>> frames;
  for (uint64_t seed : {1, 2}) {
    const auto [color, info] = smooth_frame(*e.net, seed);
    frames.push_back(network_inputs(g, color, info));
  }
  e.calibration = calibrate(g, frames, CalibrationMethod::Max);
  ExportOptions o;
  o.width = kWidth;
  o.height = kHeight;
  o.int8 = e.calibration;
  e.exported = export_network(*e.net, file, o);
  std::ifstream in(file, std::ios::binary);
  EXPECT_TRUE(e.model.ParseFromIstream(&in));
  return e;
}

std::string metadata(const onnx::ModelProto& m, const std::string& key) {
  for (const auto& p : m.metadata_props())
    if (p.key() == key) return p.value();
  return "";
}

}  // namespace int8_export_test

using namespace int8_export_test;

TEST(Int8Export, ConvolutionsReadQuantizedInputsAndInt8WeightsExceptTheWideOnes) {
  const auto dir = test::scratch_dir("int8-export");
  const Int8Export e = export_int8(test::small_spec("pan", "lr"), dir / "pan.onnx");
  const graph::Graph g = e.net->describe(false);
  const std::vector<bool> low = low_precision_convs(g);
  std::map<std::string, const onnx::NodeProto*> producer;
  std::map<std::string, const onnx::TensorProto*> initializers;
  for (const auto& n : e.model.graph().node())
    for (const auto& o : n.output()) producer[o] = &n;
  for (const auto& t : e.model.graph().initializer()) initializers[t.name()] = &t;
  int int8_convs = 0, quantize = 0;
  for (const auto& n : e.model.graph().node()) quantize += n.op_type() == "QuantizeLinear";
  for (size_t i = 0; i < g.ops.size(); ++i) {
    const auto& op = g.ops[i];
    if (op.kind != graph::OpKind::Conv) continue;
    SCOPED_TRACE(op.name);
    const onnx::NodeProto* conv = nullptr;
    for (const auto& n : e.model.graph().node())
      if (n.op_type() == "Conv" && n.name() == op.name) conv = &n;
    ASSERT_NE(conv, nullptr);
    const auto from = [&](int input) { return producer.count(conv->input(input)) ? producer.at(conv->input(input)) : nullptr; };
    if (!low[i]) {  // float32: the weight is a float initializer
      ASSERT_EQ(initializers.count(conv->input(1)), 1u);
      EXPECT_EQ(initializers.at(conv->input(1))->data_type(), onnx::TensorProto::FLOAT);
      continue;
    }
    ++int8_convs;
    for (int input = 0; input < conv->input_size(); ++input) {
      ASSERT_NE(from(input), nullptr);
      EXPECT_EQ(from(input)->op_type(), "DequantizeLinear");
    }
    // The activation comes from a QuantizeLinear; the weight is int8 and the bias int32, per
    // output channel (axis 0).
    EXPECT_EQ(producer.at(from(0)->input(0))->op_type(), "QuantizeLinear");
    EXPECT_EQ(initializers.at(from(1)->input(0))->data_type(), onnx::TensorProto::INT8);
    EXPECT_EQ(initializers.at(from(1)->input(1))->dims(0), op.weight.size(0));
    if (conv->input_size() > 2) {
      EXPECT_EQ(initializers.at(from(2)->input(0))->data_type(), onnx::TensorProto::INT32);
    }
    // Its result is quantized again.
    int consumers = 0;
    for (const auto& n : e.model.graph().node())
      for (const auto& in : n.input())
        if (in == conv->output(0)) {
          ++consumers;
          EXPECT_EQ(n.op_type(), "QuantizeLinear");
        }
    EXPECT_EQ(consumers, 1);
  }
  EXPECT_GT(int8_convs, 0);
  // One pair per int8 convolution's result, and one per value they read (shared by its readers).
  std::set<int> read;
  for (size_t i = 0; i < g.ops.size(); ++i)
    if (low[i]) read.insert(g.ops[i].inputs[0]);
  EXPECT_EQ(quantize, int8_convs + static_cast<int>(read.size()));
  EXPECT_EQ(metadata(e.model, "cgsr.precision"), "int8");
  const Calibration recorded =
      calibration_from_json(nlohmann::json::parse(metadata(e.model, "cgsr.calibration")), "test");
  EXPECT_EQ(recorded.ranges, e.calibration.ranges);
  EXPECT_EQ(recorded.frames, 2);
  std::filesystem::remove_all(dir);
}

// ONNX Runtime runs the QDQ file within the stated tolerance of the fused path's int8 output,
// for every backbone with and without rendering information.
TEST(Int8Export, OnnxRuntimeAgreesWithTheFusedInt8Path) {
  const auto dir = test::scratch_dir("int8-ort");
  std::vector<VerifyCase> cases;
  std::vector<torch::Tensor> fp32;
  for (const auto& c : test::all_network_cases()) {
    if (c.source != "" && c.source != "lr" && c.source != "hr_pooled") continue;
    const std::string stem = c.backbone + (c.source.empty() ? "" : "_" + c.source);
    Int8Export e = export_int8(test::small_spec(c.backbone, c.source), dir / (stem + ".onnx"));
    FusedGraph::Options options;
    options.precision = Precision::Int8;
    options.calibration = e.calibration;
    auto int8 = std::make_shared<FusedGraph>(e.net->describe(), options);
    const ReferenceForward forward = [int8](const torch::Tensor& color, const torch::Tensor& info) {
      return int8->run(color, info);
    };
    VerifyCase v;
    v.label = c.name();
    v.file = e.exported.file;
    const auto [color, info] = smooth_frame(*e.net, 3);
    add_verify_inputs(v, *e.net, export_inputs(e.exported.signature, color, info), forward);
    fp32.push_back(e.net->forward(color, info));
    cases.push_back(v);
  }
  VerifyOptions options;
  options.runtimes = {Runtime::OnnxRuntime};
  options.tolerance = 0.05;
  const VerifyReport report = verify_exports(cases, options);
  EXPECT_TRUE(report.ok()) << report.table();
  std::printf("%s", report.table().c_str());
  // The int8 outputs really are quantized: they differ from float32.
  for (size_t i = 0; i < cases.size(); ++i)
    EXPECT_GT((cases[i].expected[0] - fp32[i]).abs().max().item<double>(), 1e-5) << cases[i].label;
  std::filesystem::remove_all(dir);
}

TEST(Int8Export, TheCommandNeedsDataAndAnOnnxFile) {
  const auto dir = test::scratch_dir("int8-cli");
  const auto out = (dir / "x.onnx").string();
  auto r = test::run_cgsr("export --model pan --precision int8 --out " + out);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.all().find("--data DIR"), std::string::npos) << r.all();
  r = test::run_cgsr("export --model pan --precision bf16 --out " + out);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.all().find("bf16 is not exported"), std::string::npos) << r.all();
  r = test::run_cgsr("export --model pan --precision int8 --data d --format torchscript --out " + out);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.all().find("int8 is exported as ONNX"), std::string::npos) << r.all();
  EXPECT_FALSE(std::filesystem::exists(out));
  std::filesystem::remove_all(dir);
}

}  // namespace cgsr
