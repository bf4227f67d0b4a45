// Exporting a hybrid-pruned model: the selector file computes DynamicSamplers' scores and choice
// in ONNX Runtime (first frames, frames with motion, odd and even grids, divisible and
// non-divisible frame sizes), every pattern file matches PatternNetworks::run, the manifest
// lists what is there, and `cgsr export` writes and verifies the directory.

#include <gtest/gtest.h>

#include <torch/torch.h>

#include <ATen/CPUGeneratorImpl.h>

#include <functional>

#include "core/atomic_file.h"
#include "core/error.h"
#include "export/hybrid_export.h"
#include "export/hybrid_verification.h"
#include "export/onnx_writer.h"
#include "export/onnxruntime_runner.h"
#include "export/selector_onnx.h"
#include "pruning/pattern_networks.h"
#include "tests/pruning/pruning_cases.h"
#include "tests/support/cli_runner.h"

namespace cgsr {
namespace {

// A small hybrid model: a PAN with a RIT, 3 nested patterns, a sampler reading `channels` on a
// `grid` x `grid` grid with random weights, and a latency table.
HybridModel make_hybrid(const std::vector<std::string>& channels, int grid, uint64_t seed) {
  torch::manual_seed(seed);
  SRNetwork net(test::small_spec("pan", 2, 2, 6, 8, /*rit=*/true));
  test::randomize(*net);
  net->eval();
  HybridModel h;
  h.pool = test::random_pool(*net, 3, seed);
  SamplerOptions so;
  so.channels = channels;
  so.grid = grid;
  so.width = 4;
  h.samplers = DynamicSamplers(so, std::vector<int>{h.pool.size()});
  {
    torch::NoGradGuard no_grad;  // spread the scores so the choice is not a near tie
    for (auto& p : h.samplers->parameters()) p.normal_(0, 0.5);
  }
  h.samplers->eval();
  h.network = net;
  h.latency = {12, 10, {2.5, 1.75, 1.0}};
  h.provenance.stage = "pruned";
  h.provenance.extra = {{"name", "tiny hybrid"}};
  return h;
}

// The scores cgsr computes, [1, K].
torch::Tensor our_scores(HybridModel& h, const torch::Tensor& info, const torch::Tensor& previous) {
  torch::NoGradGuard no_grad;
  const auto& o = h.samplers->options();
  return h.samplers->forward(sampler_input(info, previous, o.render_channels(), o.grid)).reshape({1, -1});
}

TEST(SelectorOnnx, PoolingMatricesAreTorchsPooling) {
  const auto x = torch::rand({1, 2, 11, 7});
  for (int64_t g : {1, 2, 3, 4, 5, 7, 9, 16}) {
    SCOPED_TRACE(g);
    const auto pooled = torch::matmul(torch::matmul(adaptive_pool_matrix(11, g), x), adaptive_pool_matrix(7, g).t());
    EXPECT_LT((pooled - torch::adaptive_avg_pool2d(x, {g, g})).abs().max().item<double>(), 1e-6);
  }
  for (int64_t g : {1, 2, 3, 4, 5, 8}) {
    SCOPED_TRACE(g);
    const auto y = torch::rand({1, 3, g, g});
    const auto m = ceil_pool_matrix(g, 2);
    EXPECT_EQ(m.size(0), (g + 1) / 2);
    const auto pooled = torch::matmul(torch::matmul(m, y), m.t());
    EXPECT_LT((pooled - torch::avg_pool2d(y, 2, 2, 0, /*ceil_mode=*/true)).abs().max().item<double>(), 1e-6);
  }
}

// Grid 5 at 12x10 takes the MatMul pooling and the odd-grid 2x2 pooling; grid 4 at 12x8 the
// AveragePool paths.
TEST(SelectorOnnx, ScoresAndChoiceMatchDynamicSamplersInOnnxRuntime) {
  struct Case {
    std::vector<std::string> channels;
    int grid;
    int64_t w, h;
  };
  const std::vector<Case> cases = {{{"depth", "edge", "motion"}, 5, 12, 10},
                                   {{"depth", "normal", "motion"}, 4, 12, 8},
                                   {{"normal_angle", "edge"}, 3, 7, 9}};
  const auto dir = test::scratch_dir("selector-onnx");
  const OnnxRuntimeRunner runner(1);
  uint64_t seed = 40;
  for (const auto& c : cases) {
    SCOPED_TRACE("grid " + std::to_string(c.grid));
    HybridModel h = make_hybrid(c.channels, c.grid, seed++);
    const auto file = dir / ("selector_" + std::to_string(c.grid) + ".onnx");
    write_file_atomic(file, selector_onnx_bytes(*h.samplers, c.w, c.h));
    const OnnxModelInfo info = inspect_onnx_file(file);
    EXPECT_EQ(info.opset, kOnnxOpset);
    bool matmul = false;
    for (const auto& [type, count] : info.op_counts) matmul = matmul || type == "MatMul";
    EXPECT_EQ(matmul, c.w % c.grid != 0 || c.h % c.grid != 0 || c.grid % 2 != 0);

    // Frames: a first one (no previous), one with small motion, one with motion far off-frame,
    // and one whose every channel differs from its previous frame.
    auto generator = at::detail::createCPUGenerator(seed);
    const auto channels = parse_channels(c.channels);
    std::vector<std::pair<torch::Tensor, torch::Tensor>> frames;  // (info, previous)
    const auto f0 = random_render_info(c.channels, 1, c.h, c.w, generator);
    auto f1 = random_render_info(c.channels, 1, c.h, c.w, generator);
    auto f2 = f1.clone();
    if (channels.back() == RenderChannel::Motion) f2.slice(1, -2).mul_(500.0);  // beyond a frame
    frames.push_back({f0, {}});
    frames.push_back({f1, f0});
    frames.push_back({f2, f1});
    frames.push_back({f0, f2});
    OrtModelJob job{file, {}};
    for (const auto& [now, before] : frames)
      job.runs.push_back({{{kSelectorInfoInput, now}, {kSelectorPreviousInput, before.defined() ? before : now}}, 0, 1});
    const auto result = runner.run_checked({job}).front();
    for (size_t i = 0; i < frames.size(); ++i) {
      SCOPED_TRACE("frame " + std::to_string(i));
      const auto expected = our_scores(h, frames[i].first, frames[i].second);
      const auto scores = find_tensor(result.runs[i].outputs, kSelectorScores);
      const auto pattern = find_tensor(result.runs[i].outputs, kSelectorPattern);
      ASSERT_TRUE(scores.defined() && pattern.defined());
      ASSERT_EQ(scores.sizes(), expected.sizes());
      EXPECT_EQ(pattern.scalar_type(), torch::kLong);
      EXPECT_EQ(pattern.numel(), 1);
      EXPECT_LT((scores - expected).abs().max().item<double>(), 1e-4);
      EXPECT_EQ(pattern.item<int64_t>(), expected.argmax(1).item<int64_t>());
    }
    // The change since the previous frame reaches the scores: frame 3 is frame 0 with a previous frame.
    EXPECT_GT((our_scores(h, f0, f2) - our_scores(h, f0, {})).abs().max().item<double>(), 1e-4);
  }
  std::filesystem::remove_all(dir);
}

TEST(HybridExport, WritesEveryPatternTheSelectorAndTheManifestAndVerifies) {
  const auto dir = test::scratch_dir("hybrid-export");
  HybridModel h = make_hybrid({"depth", "edge", "motion"}, 5, 7);
  ExportOptions o;
  o.width = 12;
  o.height = 10;
  const HybridExport e = export_hybrid(h, dir / "deploy", o);

  // The manifest lists every file, and they exist.
  const auto m = test::read_json(dir / "deploy" / kHybridManifestFile);
  EXPECT_EQ(m["format_version"], kHybridManifestVersion);
  EXPECT_EQ(m["scale"], 2);
  EXPECT_EQ(m["lr_size"]["width"], 12);
  ASSERT_EQ(m["patterns"].size(), 3u);
  PatternNetworks patterns(*h.network, h.pool);
  for (int k = 0; k < 3; ++k) {
    const auto& p = m["patterns"][k];
    EXPECT_EQ(p["file"], "pattern_" + std::to_string(k) + ".onnx");
    EXPECT_TRUE(std::filesystem::exists(dir / "deploy" / p["file"].get<std::string>()));
    EXPECT_EQ(p["macs"].get<int64_t>(), patterns.cost(k, 12, 10).macs);
    EXPECT_DOUBLE_EQ(p["channel_fraction"].get<double>(), h.pool.channel_fraction(k));
    EXPECT_DOUBLE_EQ(p["latency_ms"].get<double>(), h.latency.median_ms[k]);
    if (k > 0) {
      EXPECT_LT(p["macs"].get<int64_t>(), m["patterns"][k - 1]["macs"].get<int64_t>());
    }
  }
  EXPECT_TRUE(std::filesystem::exists(dir / "deploy" / m["selector"]["file"].get<std::string>()));
  EXPECT_EQ(m["selector"]["inputs"][0]["name"], kSelectorInfoInput);
  EXPECT_EQ(m["selector"]["inputs"][1]["name"], kSelectorPreviousInput);
  EXPECT_EQ(m["selector"]["inputs"][0]["shape"], nlohmann::json({1, 4, 10, 12}));  // depth, edge, motion (2)
  EXPECT_EQ(m["selector"]["channels"][2]["name"], "motion");
  EXPECT_EQ(m["selector"]["channels"][2]["first_row"], 2);
  EXPECT_EQ(m["selector"]["grid"], 5);
  EXPECT_EQ(m["network"]["inputs"][1]["name"], "lr_render_info");
  EXPECT_EQ(m["latency_table"]["median_ms"], nlohmann::json({2.5, 1.75, 1.0}));
  EXPECT_EQ(m["latency_table"]["lr_size"]["height"], 10);

  // Every pattern in ONNX Runtime and OpenCV DNN, the selector in ONNX Runtime on three frames.
  const VerifyReport report = verify_hybrid_export(h, e, VerifyOptions(), 3);
  EXPECT_TRUE(report.ok()) << report.table();
  EXPECT_EQ(report.failed(), 0) << report.table();
  EXPECT_EQ(report.skipped(), 0) << report.table();
  int pattern_checks = 0, selector_checks = 0;
  for (const auto& c : report.checks) {
    (c.label == "selector" ? selector_checks : pattern_checks)++;
    EXPECT_LE(c.max_abs_error, 1e-4) << c.label << " " << runtime_name(c.runtime);
  }
  EXPECT_EQ(pattern_checks, 3 * 2);
  EXPECT_EQ(selector_checks, 3);
  std::filesystem::remove_all(dir);
}

TEST(HybridExport, TorchScriptPatternsRunInLibTorch) {
  const auto dir = test::scratch_dir("hybrid-export-ts");
  HybridModel h = make_hybrid({"edge", "motion"}, 4, 9);
  ExportOptions o;
  o.format = ExportFormat::TorchScript;
  o.width = 12;
  o.height = 8;
  const HybridExport e = export_hybrid(h, dir, o);
  for (int k = 0; k < 3; ++k) EXPECT_TRUE(std::filesystem::exists(dir / ("pattern_" + std::to_string(k) + ".pt")));
  EXPECT_TRUE(std::filesystem::exists(dir / kSelectorFile));  // the selector is ONNX whatever the format
  VerifyOptions v;
  v.runtimes = {Runtime::LibTorch, Runtime::OnnxRuntime};
  const VerifyReport report = verify_hybrid_export(h, e, v, 5);
  EXPECT_TRUE(report.ok()) << report.table();
  EXPECT_EQ(report.passed(), 3 + 3) << report.table();
  std::filesystem::remove_all(dir);
}

TEST(HybridExport, BadInputsAreClearErrors) {
  const auto dir = test::scratch_dir("hybrid-export-errors");
  HybridModel h = make_hybrid({"depth"}, 4, 11);
  ExportOptions o;
  o.width = 12;
  o.height = 10;
  const auto expect_error = [](const std::function<void()>& f, const std::string& part) {
    try {
      f();
      ADD_FAILURE() << "no error, expected one mentioning '" << part << "'";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
  };
  // A plain model file where a hybrid one is needed.
  save_model(dir / "plain.cgsr", *h.network);
  expect_error([&] { export_hybrid_file(dir / "plain.cgsr", dir / "out", o); }, "not a hybrid-pruned model");
  expect_error([&] { export_hybrid_file(dir / "plain.cgsr", dir / "out", o); }, "plain.cgsr");
  // An output directory that cannot exist: below a regular file.
  write_file_atomic(dir / "a_file", "x");
  expect_error([&] { export_hybrid(h, dir / "a_file" / "deploy", o); }, "cannot create the output directory");
  expect_error([&] { export_hybrid(h, dir / "a_file" / "deploy", o); }, "a_file");
  // A size-free export: the selector's pooling is fixed to one size.
  ExportOptions dynamic = o;
  dynamic.dynamic_size = true;
  expect_error([&] { export_hybrid(h, dir / "dyn", dynamic); }, "fixed frame size");
  // A model without its sampler.
  HybridModel broken = h;
  broken.samplers = DynamicSamplers(nullptr);
  expect_error([&] { export_hybrid(broken, dir / "broken", o); }, "no dynamic sampler");
  std::filesystem::remove_all(dir);
}

TEST(HybridExport, TheExportCommandWritesAndVerifiesTheDirectory) {
  const auto dir = test::scratch_dir("hybrid-export-cli");
  save_hybrid_model(dir / "pruned.cgsr", make_hybrid({"depth", "edge", "motion"}, 4, 13));
  const auto out = dir / "deploy";
  const auto r = test::run_cgsr("export --model " + (dir / "pruned.cgsr").string() + " --input 12x10 --verify --out " +
                                out.string());
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("3 patterns"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("9 passed, 0 failed, 0 skipped"), std::string::npos) << r.out;  // 3 x 2 runtimes + 3 frames
  EXPECT_NE(r.out.find("selector"), std::string::npos) << r.out;
  for (const char* f : {"pattern_0.onnx", "pattern_1.onnx", "pattern_2.onnx", "selector.onnx", "manifest.json"})
    EXPECT_TRUE(std::filesystem::exists(out / f)) << f;
  const auto results = test::read_json(out / "results.json");
  EXPECT_EQ(results["verification"]["passed"], 9);
  EXPECT_EQ(results["verification"]["failed"], 0);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace cgsr
