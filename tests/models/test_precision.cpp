// Reduced precision on the fused path: INT8 quantization round trips, calibration, and BF16 and
// INT8 networks that stay finite and near float32, with the first and last layers kept wide.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <algorithm>
#include <limits>

#include "core/error.h"
#include "models/fused_graph.h"
#include "models/precision.h"
#include "models/subnet.h"
#include "tests/models/model_cases.h"
#include "tests/models/numerics_cases.h"

using namespace cgsr;
using namespace cgsr::test;

namespace {

using Inputs = std::vector<std::pair<std::string, torch::Tensor>>;

// Smooth, image-like inputs in [0, 1] (random noise would make every activation an outlier):
// colour gradients and the rendering channels of small_spec's RIT.
Inputs frame_inputs(const graph::Graph& g, int64_t h, int64_t w, uint64_t seed) {
  torch::manual_seed(seed);
  const auto smooth = [&](int64_t c, int64_t hh, int64_t ww) {
    const auto coarse = torch::rand({1, c, 4, 4});
    return torch::upsample_bilinear2d(coarse, {hh, ww}, false);
  };
  Inputs in = {{"color", smooth(3, h, w)}};
  for (const char* name : {"info", "info_hr"})
    if (g.has_input(name)) {
      const auto& v = g.values[g.input(name)];
      in.emplace_back(name, smooth(graph::layout_width(v.layout), h * v.factor, w * v.factor));
    }
  return in;
}

double psnr_against(const torch::Tensor& got, const torch::Tensor& reference) {
  const double peak = std::max(1e-6, reference.abs().max().item<double>());
  const double mse = (got - reference).pow(2).mean().item<double>();
  return 10 * std::log10(peak * peak / std::max(mse, 1e-30));
}

}  // namespace

TEST(Precision, QuantizeDequantizeRoundTripsWithinHalfAStep) {
  torch::manual_seed(1);
  const auto x = torch::randn({1000}) * 3;
  const float s = int8_scale(x.abs().max().item<double>());
  const auto q = quantize_int8(x, s);
  EXPECT_EQ(q.scalar_type(), torch::kChar);
  EXPECT_LE((dequantize_int8(q, s) - x).abs().max().item<double>(), s / 2 * (1 + 1e-5));
  EXPECT_EQ(q.abs().max().item<int>(), 127);  // the largest value uses the whole range
  // Beyond the range: saturated, symmetric (never -128).
  const auto far = quantize_int8(torch::tensor({-1e9f, 1e9f, 0.f}), 1.f);
  EXPECT_EQ(far[0].item<int>(), -127);
  EXPECT_EQ(far[1].item<int>(), 127);
  EXPECT_EQ(far[2].item<int>(), 0);
  // A quantized value is its own round trip.
  EXPECT_TRUE(torch::equal(quantize_int8(dequantize_int8(q, s), s), q));
  EXPECT_THROW(quantize_int8(x, 0.f), Error);
  EXPECT_GT(int8_scale(0.0), 0.f);
}

TEST(Precision, ChannelScalesAreEachChannelsLargestMagnitude) {
  auto w = torch::zeros({3, 2, 1, 1});
  w[0][1][0][0] = -2.54f;
  w[1][0][0][0] = 1.27f;
  const auto s = int8_channel_scales(w);
  EXPECT_NEAR(s[0].item<float>(), 0.02f, 1e-7);
  EXPECT_NEAR(s[1].item<float>(), 0.01f, 1e-7);
  EXPECT_GT(s[2].item<float>(), 0.f);  // an all-zero channel still has a step
}

TEST(Precision, CalibrationIsDeterministicAndCoversEveryOp) {
  SRNetwork net = perturbed_network(small_spec("pan", "lr"), 3);
  net->eval();
  const graph::Graph g = net->describe();
  const std::vector<Inputs> frames = {frame_inputs(g, 12, 16, 1), frame_inputs(g, 12, 16, 2)};
  const Calibration a = calibrate(g, frames, CalibrationMethod::Max);
  const Calibration b = calibrate(g, frames, CalibrationMethod::Max);
  EXPECT_EQ(a.ranges, b.ranges);
  EXPECT_EQ(a.frames, 2);
  for (const auto& op : g.ops) EXPECT_EQ(a.ranges.count(g.values[op.output].name), 1u) << op.name;
  // The percentile bound never exceeds the maximum, and more frames never shrink a range.
  const Calibration p = calibrate(g, frames, CalibrationMethod::Percentile);
  const Calibration one = calibrate(g, {frames[0]}, CalibrationMethod::Max);
  for (const auto& [name, range] : a.ranges) {
    EXPECT_LE(p.range(name), range) << name;
    EXPECT_LE(one.range(name), range) << name;
  }
  EXPECT_THROW(a.range("no such value"), Error);
  EXPECT_THROW(calibrate(g, {}, CalibrationMethod::Max), Error);
  Inputs bad = frames[0];
  bad[0].second[0][0][0][0] = std::numeric_limits<float>::infinity();
  EXPECT_THROW(calibrate(g, {bad}, CalibrationMethod::Max), Error);
}

// The first and last convolutions compute in float32, the others in the low format, and PAN's
// attention maps (sigmoid outputs) stay float32.
TEST(Precision, WideLayersStayFloat32) {
  SRNetwork net = perturbed_network(small_spec("pan", "lr"), 4);
  net->eval();
  const graph::Graph g = net->describe();
  const Inputs in = frame_inputs(g, 12, 16, 5);
  for (Precision precision : {Precision::Int8, Precision::Bf16}) {
    SCOPED_TRACE(enum_name(precision));
    FusedGraph::Options options;
    options.precision = precision;
    options.calibration = calibrate(g, {in}, CalibrationMethod::Max);
    FusedGraph fused(g, options);
    fused.run(in);
    const auto precision_of = [&](const std::string& op) {
      for (const auto& s : fused.steps())
        if (s.kind == "conv" && s.ops[0] == op) return s.precision;
      return std::string("not a conv step");
    };
    const std::string low = enum_name(precision);
    EXPECT_EQ(precision_of("backbone.conv_first"), "fp32");
    EXPECT_EQ(precision_of("backbone.conv_last"), "fp32");
    EXPECT_EQ(precision_of("backbone.blocks.0.pa_conv.k3"), low);
    EXPECT_EQ(precision_of("backbone.trunk_conv"), low);
    for (const auto& op : g.ops) {
      if (op.kind == graph::OpKind::Conv && op.inputs[0] == g.input("info")) {
        EXPECT_EQ(precision_of(op.name), "fp32");
      }
    }
    int converted = 0;
    for (const auto& s : fused.steps()) {
      converted += s.kind == "convert";
      EXPECT_EQ(s.implementation.find("ref"), std::string::npos) << s.kind << " " << s.ops[0];
    }
    EXPECT_GT(converted, 0);  // the float32 residuals are converted once for their readers
  }
  FusedGraph::Options uncalibrated;
  uncalibrated.precision = Precision::Int8;
  EXPECT_THROW(FusedGraph(g, uncalibrated), Error);  // no calibration
  // Which convolutions compute low can be given (the latency table times a lone one so): the
  // first layer too; marking an op that is not a convolution, or a list of another length, is an error.
  FusedGraph::Options first;
  first.precision = Precision::Int8;
  first.calibration = calibrate(g, {in}, CalibrationMethod::Max);
  first.low_convs = low_precision_convs(g);
  for (size_t i = 0; i < g.ops.size(); ++i)
    first.low_convs[i] = first.low_convs[i] || g.ops[i].name == "backbone.conv_first";
  FusedGraph forced(g, first);
  forced.run(in);
  const auto conv_first = std::find_if(forced.steps().begin(), forced.steps().end(), [](const auto& s) {
    return s.kind == "conv" && s.ops[0] == "backbone.conv_first";
  });
  ASSERT_NE(conv_first, forced.steps().end());
  EXPECT_EQ(conv_first->precision, "int8");
  FusedGraph::Options wrong = first;
  wrong.low_convs.pop_back();
  EXPECT_THROW(FusedGraph(g, wrong).run(in), Error);
  wrong.low_convs = std::vector<bool>(g.ops.size(), true);
  EXPECT_THROW(FusedGraph(g, wrong).run(in), Error);
}

// Simulated INT8 (quantization-aware fine-tuning) computes what the fused INT8 path does, far
// closer to it than float32 is, and passes gradients to the network's weights through the rounding.
TEST(Precision, SimulatedInt8MatchesTheFusedPathAndPassesGradients) {
  SRNetwork net = perturbed_network(small_spec("pan", "lr"), 5);
  net->eval();
  const graph::Graph g = net->describe();
  const Inputs calibration_frame = frame_inputs(g, 12, 16, 3), in = frame_inputs(g, 12, 16, 4);
  const Calibration c = calibrate(g, {calibration_frame}, CalibrationMethod::Max);
  FusedGraph::Options int8_options;
  int8_options.precision = Precision::Int8;
  int8_options.calibration = c;
  FusedGraph int8(g, int8_options);
  const torch::Tensor fused = int8.run(in).front().second;
  const torch::Tensor fp32 = graph::run(g, in).front().second;
  const torch::Tensor simulated = run_fake_int8(g, in, c).front().second;
  const double to_fused = (simulated - fused).abs().max().item<double>();
  const double fp32_to_fused = (fp32 - fused).abs().max().item<double>();
  EXPECT_GT(fp32_to_fused, 0);
  EXPECT_LT(to_fused, 0.25 * fp32_to_fused) << to_fused << " against " << fp32_to_fused;
  // Through a differentiable graph, a loss of the simulated output reaches the weights.
  net->train();
  const graph::Graph d = subnet_graph(*net, full_subnet(net->spec()), /*training=*/false, /*differentiable=*/true);
  run_fake_int8(d, in, c).front().second.square().mean().backward();
  double gradient = 0;
  for (const auto& p : net->parameters())
    if (p.grad().defined()) gradient += p.grad().abs().sum().item<double>();
  EXPECT_GT(gradient, 0);
}

// Every backbone, plain and with a RIT: INT8 and BF16 outputs on frames the calibration did not
// see stay within a bound of float32's.
TEST(Precision, ReducedPrecisionStaysNearFloat32) {
  for (const auto& c : all_network_cases()) {
    SCOPED_TRACE(c.name());
    SRNetwork net = perturbed_network(small_spec(c.backbone, c.source), 7);
    net->eval();
    const graph::Graph g = net->describe();
    const Calibration calibration =
        calibrate(g, {frame_inputs(g, 12, 16, 8), frame_inputs(g, 12, 16, 9)}, CalibrationMethod::Max);
    const Inputs in = frame_inputs(g, 12, 16, 10);
    const torch::Tensor reference = FusedGraph(g).run(in)[0].second;
    for (auto [precision, bound_db] : {std::pair{Precision::Bf16, 35.0}, {Precision::Int8, 30.0}}) {
      FusedGraph::Options options;
      options.precision = precision;
      options.calibration = calibration;
      const torch::Tensor got = FusedGraph(g, options).run(in)[0].second;
      ASSERT_TRUE(torch::isfinite(got).all().item<bool>());
      const double db = psnr_against(got, reference);
      std::printf("%-28s %s: %.1f dB against fp32\n", c.name().c_str(), enum_name(precision).c_str(), db);
      EXPECT_GE(db, bound_db) << enum_name(precision);
    }
  }
}

// Black, white, saturated and far-depth frames: finite, and within a bound of float32 (values
// beyond the calibrated range saturate, so the bound is looser than on ordinary frames).
TEST(Precision, ExtremeFramesStayFiniteAndBounded) {
  SRNetwork net = perturbed_network(small_spec("pan", "lr"), 11);
  net->eval();
  const graph::Graph g = net->describe();
  FusedGraph::Options options;
  options.precision = Precision::Int8;
  options.calibration = calibrate(g, {frame_inputs(g, 12, 16, 12)}, CalibrationMethod::Max);
  FusedGraph int8(g, options);
  options.precision = Precision::Bf16;
  FusedGraph bf16(g, options);
  FusedGraph fp32(g);
  // Extreme colours with ordinary information, then extreme information (LR here).
  const int64_t h = 12, w = 16;
  const Inputs ordinary = frame_inputs(g, h, w, 13);
  std::vector<InputCase> cases;
  for (const auto& [name, color] : extreme_colours(h, w)) cases.push_back({name, color, ordinary[1].second});
  for (const auto& c : extreme_information(ordinary[0].second, extreme_depths(h, w, net->spec().rit.depth_encoding)))
    cases.push_back(c);
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const auto in = network_inputs(g, c.color, c.info);
    const torch::Tensor reference = fp32.run(in)[0].second;
    for (FusedGraph* f : {&int8, &bf16}) {
      const torch::Tensor got = f->run(in)[0].second;
      ASSERT_TRUE(torch::isfinite(got).all().item<bool>());
      const double range = std::max(1.0, reference.abs().max().item<double>());
      EXPECT_LE((got - reference).abs().max().item<double>(), 0.5 * range);
    }
  }
}
