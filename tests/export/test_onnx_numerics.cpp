// Issue 19 for the exported ONNX file: every backbone, plain and with a RIT from every source,
// written by our ONNX writer and run in ONNX Runtime on the extreme inputs of the network numerics
// tests (tests/models/numerics_cases.h), gives finite outputs equal to the LibTorch engine's
// (itself checked against the fused engine) on the same input.

#include <gtest/gtest.h>

#include <torch/torch.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "core/tensor_checks.h"
#include "export/exporter.h"
#include "export/onnx_writer.h"
#include "export/onnxruntime_runner.h"
#include "export/torchscript_writer.h"
#include "export/verification.h"
#include "tests/models/numerics_cases.h"
#include "tests/support/cli_runner.h"

namespace cgsr {
namespace {

using test::Engines;

// ONNX Runtime and LibTorch compute the same float32 graph in other summation orders (and the
// bicubic skip as a conv): the verification's default tolerance, as in test_verification.cpp.
// On these inputs the outputs stay below 2 and differ by at most about 1e-6.
constexpr double kTolerance = 1e-4;

// Exported files, each with named inputs and the engines' output on them, verified together in
// one ONNX Runtime process.
class OnnxNumerics {
 public:
  explicit OnnxNumerics(const std::string& name) : dir_(test::scratch_dir(name)) {}
  ~OnnxNumerics() { std::filesystem::remove_all(dir_); }

  // Exports `e`'s network: size-free by default, else at `width` x `height` (batch 1).
  void export_file(const std::string& label, const Engines& e, int64_t width = 0, int64_t height = 0) {
    ExportOptions o;
    o.dynamic_size = width == 0;
    o.width = width;
    o.height = height;
    const ExportedModel m = export_network(*e.net, dir_ / ("m" + std::to_string(cases_.size()) + ".onnx"), o);
    cases_.push_back({label, m.file, m.format, {}, {}, {}});
    signatures_.push_back(m.signature);
  }

  // An input for the last exported file; its expected output is the engines' (finite and equal).
  void add(Engines& e, const std::string& name, const torch::Tensor& color, const torch::Tensor& info) {
    VerifyCase& c = cases_.back();
    c.inputs.push_back(export_inputs(signatures_.back(), color, info));
    c.expected.push_back(e.expect_finite(color, info, c.label + ", " + name));
    input_names_.push_back(c.label + ", " + name + " " + shape_string(color));
  }

  // Runs everything. The expected outputs are finite, so a finite difference means a finite ONNX
  // output of the right shape (max_abs_error is infinite for NaN, infinity or another shape).
  void expect_match() const {
    VerifyOptions options;
    options.runtimes = {Runtime::OnnxRuntime};
    options.tolerance = kTolerance;
    const VerifyReport report = verify_exports(cases_, options);
    ASSERT_EQ(report.checks.size(), input_names_.size());  // one check per input, in order
    for (size_t i = 0; i < input_names_.size(); ++i) {
      const RuntimeCheck& check = report.checks[i];
      SCOPED_TRACE(input_names_[i]);
      EXPECT_TRUE(check.ran && check.error.empty()) << check.error;
      EXPECT_TRUE(std::isfinite(check.max_abs_error)) << "non-finite ONNX output";
      EXPECT_LE(check.max_abs_error, kTolerance);
    }
  }

 private:
  std::filesystem::path dir_;
  std::vector<VerifyCase> cases_;
  std::vector<ExportSignature> signatures_;
  std::vector<std::string> input_names_;
};

torch::Tensor random_info(std::vector<int64_t> shape) { return torch::rand(shape); }

TEST(OnnxNumerics, ExtremeColoursMatchTheEnginesForEveryNetwork) {
  OnnxNumerics run("onnx-numerics-colours");
  uint64_t seed = 3900;
  for (const auto& c : test::all_network_cases()) {
    Engines e(test::small_spec(c.backbone, c.source), ++seed);
    run.export_file(c.name(), e);
    const auto colours = test::extreme_colours(5, 7);
    const auto info = e.info_for(colours[0].second, random_info);
    for (const auto& [name, colour] : colours) run.add(e, name, colour, info);
  }
  run.expect_match();
}

// Size-free files at every small size, and files exported at 1x1, the smallest fixed size. PAN
// with a bicubic skip too: its conv form pads the edges by 2, more than a 1x1 frame has.
TEST(OnnxNumerics, FramesSmallerThanAKernelMatchTheEnginesForEveryNetwork) {
  OnnxNumerics run("onnx-numerics-small");
  uint64_t seed = 3950;
  for (int scale : {2, 3, 4}) {
    std::vector<std::pair<std::string, ArchSpec>> specs;
    for (const auto& c : test::all_network_cases())
      specs.emplace_back(c.name(), test::small_spec(c.backbone, c.source, scale));
    ArchSpec bicubic = test::small_spec("pan", "", scale);
    bicubic.image_skip = ImageSkip::Bicubic;
    specs.emplace_back("pan plain, bicubic skip", resolve_spec(bicubic));
    for (const auto& [name, spec] : specs) {
      const std::string label = name + " x" + std::to_string(scale);
      Engines e(spec, ++seed);
      run.export_file(label, e);
      for (const auto& shape : test::small_frame_shapes()) {
        const auto color = torch::rand(shape);
        run.add(e, "random", color, e.info_for(color, random_info));
      }
      run.export_file(label + ", fixed 1x1", e, 1, 1);
      const auto color = torch::rand({1, 3, 1, 1});
      run.add(e, "random", color, e.info_for(color, random_info));
    }
  }
  run.expect_match();
}

// All sky (no geometry), every pixel an edge, depth at near 1e-3 and far 1e6 in every encoding.
TEST(OnnxNumerics, ExtremeRenderingInformationMatchesTheEnginesForEveryRitSource) {
  OnnxNumerics run("onnx-numerics-information");
  const int64_t h = 4, w = 5;
  uint64_t seed = 4000;
  for (const auto& c : test::all_network_cases()) {
    if (c.source.empty()) continue;
    Engines e(test::small_spec(c.backbone, c.source), ++seed);
    run.export_file(c.name(), e);
    const int64_t f = e.net->rit()->info_factor();
    for (const auto& encoding : EnumNames<DepthEncoding>::names()) {
      const auto depths = test::extreme_depths(h * f, w * f, enum_from_name<DepthEncoding>(encoding));
      for (const auto& input : test::extreme_information(torch::rand({1, 3, h, w}), depths))
        run.add(e, input.name + ", " + encoding + " depth", input.color, input.info);
    }
  }
  run.expect_match();
}

// The Sample op's rounding and clamping in the exported files: a graph whose offsets are the
// input's own R and G channels (nearest-upsampled through a fixed 1x1 conv), so the test sets
// every offset, at an 8x8 frame (power-of-two sizes keep the normalized grid exact): exact
// halves (round half to even, nearbyint), positions beyond the border (clamped) and others.
// ONNX Runtime (fixed and dynamic size) and TorchScript must pick the very pixels our kernel
// picks: the outputs are equal, not close.
TEST(OnnxNumerics, SampleRoundsHalvesToEvenAndClampsAsOurKernelDoes) {
  const int64_t size = 8, r = 2;
  graph::Builder g;
  const int color = g.input("color", graph::fixed_layout("rgb", 3), 1);
  const int up = g.resize(color, r, graph::ResizeMode::Nearest);
  const auto pick_rg = torch::tensor({1.f, 0.f, 0.f, 0.f, 1.f, 0.f}).view({2, 3, 1, 1});
  const int offsets = g.conv("offsets", up, pick_rg, torch::Tensor(), 0, graph::fixed_layout("offsets", 2), false);
  for (const auto mode : {graph::ResizeMode::Nearest, graph::ResizeMode::Bilinear, graph::ResizeMode::Bicubic}) {
    SCOPED_TRACE(graph::resize_mode_name(mode));
    graph::Builder copy = g;
    copy.output("image", copy.sample(color, offsets, mode));
    const graph::Graph graph = copy.finish();
    // Output column j of block (i, j) sits at j / 2 - 0.25: odd quarters make .5 ties half the time.
    auto generator = at::detail::createCPUGenerator(17);
    const auto quarters = torch::randint(-12, 12, {1, 2, size, size}, generator) * 2 + 1;  // odd
    auto rg = quarters.to(torch::kFloat) / 4;
    rg.select(3, 0).fill_(-40.f);  // far beyond the left and top borders
    rg.select(2, size - 1).fill_(37.25f);
    const auto ids = torch::arange(size * size, torch::kFloat).view({1, 1, size, size});
    const auto x = torch::cat({rg, ids}, 1);
    const auto ours = graph::run(graph, {{"color", x}})[0].second;
    if (mode == graph::ResizeMode::Nearest) {
      // Ties occurred, and each resolved to the even column or row.
      const auto positions = torch::arange(size * r, torch::kFloat) / r - 0.25;
      const auto dx = graph::apply_resize(rg, r, graph::ResizeMode::Nearest).select(1, 0)[0];
      const auto at = positions.view({1, -1}) + dx;
      const auto ties = (at - at.floor()) == 0.5;
      ASSERT_GT(ties.sum().item<int64_t>(), 10);
      const auto picked_column = torch::remainder(ours.select(1, 2)[0], size);
      const auto expected_column = torch::clamp(torch::round(at), 0, size - 1);  // torch::round: half to even
      EXPECT_TRUE(torch::equal(picked_column, expected_column));
    }
    const auto dir = test::scratch_dir("sample-rounding");
    const OnnxRuntimeRunner runner(1);
    for (const bool dynamic : {false, true}) {
      OnnxOptions o;
      o.width = size;
      o.height = size;
      o.dynamic_size = dynamic;
      const auto file = dir / (std::string(dynamic ? "dynamic" : "fixed") + ".onnx");
      write_onnx(file, graph, o);
      EXPECT_EQ(inspect_onnx_file(file).opset, kOnnxGridSampleOpset);
      const auto result = runner.run_checked({OrtModelJob{file, {OrtRun{{{kExportColorInput, x}}, 0, 1}}}}).front();
      const auto theirs = find_tensor(result.runs.at(0).outputs, kExportOutput);
      ASSERT_TRUE(theirs.defined());
      if (mode == graph::ResizeMode::Nearest)
        EXPECT_TRUE(torch::equal(theirs, ours)) << (dynamic ? "dynamic" : "fixed");
      else
        EXPECT_LT((theirs - ours).abs().max().item<double>(), 1e-5) << (dynamic ? "dynamic" : "fixed");
    }
    auto module = torchscript_module(graph);
    const auto scripted = module.forward({x}).toTensor();
    EXPECT_TRUE(torch::equal(scripted, ours));
    std::filesystem::remove_all(dir);
  }
}

}  // namespace
}  // namespace cgsr
