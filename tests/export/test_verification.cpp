// Every network exports in both formats and runs in every runtime (ONNX Runtime, OpenCV DNN,
// LibTorch, Python torch) within 1e-4 of our own forward pass.

#include <gtest/gtest.h>

#include <torch/torch.h>

#include <algorithm>
#include <map>
#include <random>
#include <set>

#include "core/runtime.h"
#include "export/exporter.h"
#include "export/verification.h"
#include "models/elastic.h"
#include "models/inherit.h"
#include "models/latency_table.h"
#include "models/subnet.h"
#include "pruning/equal_latency_controls.h"
#include "search/search_loop.h"
#include "search/subnet_evaluator.h"
#include "tests/export/export_cases.h"
#include "tests/support/cli_runner.h"
#include "tests/support/elastic_options.h"
#include "tests/support/tiny_data.h"

namespace cgsr {
namespace {

constexpr int64_t kWidth = 12, kHeight = 10;

TEST(Verification, EveryNetworkMatchesOurForwardInEveryRuntime) {
  const auto dir = test::scratch_dir("export-verify");
  std::vector<VerifyCase> cases;
  std::vector<std::string> names;
  uint64_t seed = 100;
  for (const auto& c : test::export_cases()) {
    SRNetwork net = test::build_network(c.spec, seed++);
    for (ExportFormat format : {ExportFormat::Onnx, ExportFormat::TorchScript}) {
      ExportOptions o;
      o.format = format;
      o.width = kWidth;
      o.height = kHeight;
      const auto file = dir / (c.name + (format == ExportFormat::Onnx ? ".onnx" : ".pt"));
      const ExportedModel m = export_network(*net, file, o);
      cases.push_back(make_verify_case(*net, m, {{kWidth, kHeight}}, seed));
      cases.back().label = c.name;
    }
  }
  const VerifyReport report = verify_exports(cases);
  // Each case ran in both runtimes of its format: nothing skipped, nothing failed; except that
  // OpenCV DNN 4.6 cannot run SRPO's GridSample, which is skipped with that reason.
  std::map<std::string, int> ran;
  int samples_by_offsets = 0;
  for (const auto& c : test::export_cases()) samples_by_offsets += c.spec.backbone == "srpo";
  for (const auto& check : report.checks) {
    SCOPED_TRACE(check.label + " in " + runtime_name(check.runtime));
    if (check.runtime == Runtime::OpenCvDnn && check.label.rfind("srpo", 0) == 0) {
      EXPECT_NE(check.skipped.find("no GridSample layer"), std::string::npos) << check.skipped;
      ++ran["opencv-dnn skipped"];
      continue;
    }
    EXPECT_TRUE(check.skipped.empty()) << check.skipped;
    EXPECT_TRUE(check.error.empty()) << check.error;
    EXPECT_TRUE(check.ran);
    EXPECT_LE(check.max_abs_error, 1e-4);
    EXPECT_GE(check.max_abs_error, 0.0);
    ++ran[runtime_name(check.runtime)];
  }
  const int n = static_cast<int>(test::export_cases().size());
  EXPECT_EQ(ran["onnxruntime"], n);
  EXPECT_GE(samples_by_offsets, 4);  // SRPO x2, x3, x4 and a CG-enhanced one
  EXPECT_EQ(ran["opencv-dnn"], n - samples_by_offsets);
  EXPECT_EQ(ran["opencv-dnn skipped"], samples_by_offsets);
  EXPECT_EQ(ran["libtorch"], n);
  EXPECT_EQ(ran["python-torch"], n);
  EXPECT_TRUE(report.ok()) << report.table();
  std::filesystem::remove_all(dir);
}

// What the search and pruning stages produce are plain specs with smaller, uneven widths, fewer
// blocks and inherited weights: a subnet of an elastic network and a magnitude-pruned network
// export and verify like any network.
// SPAN's too: its subnets narrow the branches, then fold them.
TEST(Verification, SearchedAndPrunedNetworksMatchInEveryRuntime) {
  const auto dir = test::scratch_dir("export-verify-searched-pruned");
  std::vector<std::pair<std::string, SRNetwork>> nets;
  for (const char* backbone : {"pan", "span"}) {
    SRNetwork parent = test::build_network(test::with_rit(default_spec(backbone, 2), "lr", "concat"), 500);
    const ElasticSpace space(parent->spec(), ElasticOptions{});
    std::mt19937_64 rng(5);
    SubnetConfig searched = space.sample(rng);
    while (searched.blocks.size() == static_cast<size_t>(space.total_blocks())) searched = space.sample(rng);
    nets.emplace_back(std::string(backbone) + "_searched", materialize_subnet(*parent, searched));
    nets.emplace_back(std::string(backbone) + "_magnitude_pruned",
                      materialize_subnet(*parent, control_subnet(*parent, ControlKind::Magnitude, 0.5)));
    for (size_t i = nets.size() - 2; i < nets.size(); ++i)
      EXPECT_LT(inference_parameter_count(*nets[i].second), inference_parameter_count(*parent)) << nets[i].first;
  }
  std::vector<VerifyCase> cases;
  for (auto [name, net] : nets) {
    for (ExportFormat format : {ExportFormat::Onnx, ExportFormat::TorchScript}) {
      ExportOptions o;
      o.format = format;
      o.width = kWidth;
      o.height = kHeight;
      const auto m = export_network(*net, dir / (name + (format == ExportFormat::Onnx ? ".onnx" : ".pt")), o);
      cases.push_back(make_verify_case(*net, m, {{kWidth, kHeight}}, 7));
    }
  }
  const VerifyReport report = verify_exports(cases);
  EXPECT_EQ(report.checks.size(), 16u);  // 4 networks x 2 formats x 2 runtimes
  EXPECT_EQ(report.passed(), 16) << report.table();
  std::filesystem::remove_all(dir);
}

// Every subnet on a search's front (an elastic network scored on rendered crops) materializes
// as a network of its own that exports to ONNX and computes in ONNX Runtime what cgsr computes;
// so do the space's smallest and full subnets (the front's size depends on the measured latency
// table, and may be one subnet on a loaded machine).
TEST(Verification, EverySubnetOnASearchFrontExportsAndMatchesInOnnxRuntime) {
  const auto dir = test::scratch_dir("export-verify-front");
  seed_everything(9);
  const Dataset data = Dataset::open(test::tiny_data());
  SRNetwork net = test::build_network(test::with_rit(default_spec("pan", 2), "hr_unshuffle+hr_fuse", "concat"), 600);
  const ElasticNetwork elastic = make_elastic(*net, test::elastic_options(8, 0.25, 4));
  LatencyTableOptions latency;
  latency.runs = 1;
  latency.calibration_subnets = 2;
  latency.check_subnets = 0;
  latency.subnet_runs = 1;
  ValidationCropOptions crops;
  crops.frames = 1;
  crops.size = 16;
  InferenceEvaluator evaluator(
      elastic.network, data, crops,
      {{Precision::Fp32, measure_latency_table(*elastic.network, elastic.space, 32, 24, latency)}});
  SearchOptions options;
  options.population = 8;
  options.generations = 2;
  SearchHistory history(dir / "history.jsonl", false);
  const SearchResult result = run_search(elastic.space, evaluator, history, options, "evolution");
  ASSERT_GE(result.front.size(), 1u);
  std::vector<SubnetConfig> subnets;
  for (const auto& point : result.front) subnets.push_back(point.subnet);
  for (const SubnetConfig& extreme : {elastic.space.smallest(), elastic.space.full()})
    if (std::find(subnets.begin(), subnets.end(), extreme) == subnets.end()) subnets.push_back(extreme);
  std::vector<VerifyCase> cases;
  for (size_t i = 0; i < subnets.size(); ++i) {
    SRNetwork subnet = materialize_subnet(*elastic.network, subnets[i]);
    subnet->eval();
    ExportOptions o;
    o.format = ExportFormat::Onnx;
    o.width = kWidth;
    o.height = kHeight;
    const auto m = export_network(*subnet, dir / ("front_" + std::to_string(i) + ".onnx"), o);
    cases.push_back(make_verify_case(*subnet, m, {{kWidth, kHeight}}, 11));
  }
  const VerifyReport report = verify_exports(cases);
  int onnxruntime = 0;
  for (const auto& check : report.checks) onnxruntime += check.runtime == Runtime::OnnxRuntime && check.passed;
  EXPECT_EQ(onnxruntime, static_cast<int>(subnets.size())) << report.table();
  EXPECT_TRUE(report.ok()) << report.table();
  std::filesystem::remove_all(dir);
}

// Size-free files (dynamic ONNX, TorchScript) verify at two different sizes; OpenCV DNN is
// skipped for dynamic ONNX with the reason.
TEST(Verification, SizeFreeFilesMatchAtTwoSizes) {
  const auto dir = test::scratch_dir("export-verify-dynamic");
  const std::vector<test::ExportCase> chosen = {
      {"pan_x3", default_spec("pan", 3)},
      {"srcnn_x4_y", test::spec_for({"srcnn", 4, "y"})},
      {"edsr_x2_rit_hr_pooled", test::with_rit(default_spec("edsr", 2), "hr_pooled", "concat")},
      {"shrunk_pan_x4_rit_lr", test::with_rit(test::shrunk_pan(4), "lr", "add")},
      {"srpo_x3", default_spec("srpo", 3)},  // its sampling grid is computed from the sizes
  };
  std::vector<VerifyCase> cases;
  uint64_t seed = 200;
  for (const auto& c : chosen) {
    SRNetwork net = test::build_network(c.spec, seed++);
    ExportOptions o;
    o.dynamic_size = true;
    const auto onnx = export_network(*net, dir / (c.name + ".onnx"), o);
    cases.push_back(make_verify_case(*net, onnx, {{kWidth, kHeight}, {7, 9}}, seed));
    o.format = ExportFormat::TorchScript;
    const auto ts = export_network(*net, dir / (c.name + ".pt"), o);
    cases.push_back(make_verify_case(*net, ts, {{kWidth, kHeight}, {7, 9}}, seed));
  }
  const VerifyReport report = verify_exports(cases);
  std::map<std::string, std::set<std::string>> sizes_by_runtime;
  for (const auto& check : report.checks) {
    SCOPED_TRACE(check.label + " in " + runtime_name(check.runtime) + " at " + check.input);
    if (check.runtime == Runtime::OpenCvDnn) {
      EXPECT_NE(check.skipped.find("fixed-size exports only"), std::string::npos) << check.skipped;
      continue;
    }
    EXPECT_TRUE(check.ran && check.passed) << check.error << check.skipped;
    EXPECT_LE(check.max_abs_error, 1e-4);
    sizes_by_runtime[runtime_name(check.runtime)].insert(check.input);
  }
  for (const char* r : {"onnxruntime", "libtorch", "python-torch"})
    EXPECT_EQ(sizes_by_runtime[r], (std::set<std::string>{"12x10", "7x9"})) << r;
  EXPECT_EQ(report.skipped(), static_cast<int>(chosen.size()) * 2);  // OpenCV at both sizes
  EXPECT_TRUE(report.ok());
  std::filesystem::remove_all(dir);
}

// A native cubic Resize runs in ONNX Runtime; OpenCV DNN 4.6 cannot run it, which is why the conv
// form is the default. The failure is reported per runtime with OpenCV's message.
TEST(Verification, NativeCubicResizeRunsInOnnxRuntimeAndFailsClearlyInOpenCv) {
  const auto dir = test::scratch_dir("export-verify-cubic");
  SRNetwork net = test::build_network(test::spec_for({"srcnn", 3, "rgb"}), 300);
  ExportOptions o;
  o.width = kWidth;
  o.height = kHeight;
  o.cubic = CubicResize::Native;
  const auto onnx = export_network(*net, dir / "srcnn_native.onnx", o);
  const VerifyReport report = verify_exports({make_verify_case(*net, onnx, {{kWidth, kHeight}}, 1)});
  ASSERT_EQ(report.checks.size(), 2u);
  EXPECT_EQ(report.checks[0].runtime, Runtime::OnnxRuntime);
  EXPECT_TRUE(report.checks[0].passed) << report.checks[0].error;
  EXPECT_EQ(report.checks[1].runtime, Runtime::OpenCvDnn);
  EXPECT_FALSE(report.checks[1].passed);
  EXPECT_NE(report.checks[1].error.find("OpenCV"), std::string::npos) << report.checks[1].error;
  EXPECT_FALSE(report.ok());
  EXPECT_NE(report.table().find("FAILED"), std::string::npos);
  EXPECT_EQ(report.to_json()["failed"], 1);
  std::filesystem::remove_all(dir);
}

TEST(Verification, NamedRuntimesThatCannotRunAFileAreErrors) {
  const auto dir = test::scratch_dir("export-verify-errors");
  SRNetwork net = test::build_network(test::shrunk_edsr(2), 400);
  ExportOptions o;
  o.dynamic_size = true;
  const auto onnx = export_network(*net, dir / "dynamic.onnx", o);
  const VerifyCase c = make_verify_case(*net, onnx, {{6, 5}}, 1);
  VerifyOptions opencv;
  opencv.runtimes = {Runtime::OpenCvDnn};
  try {
    verify_exports({c}, opencv);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("fixed-size exports only"), std::string::npos) << e.what();
  }
  VerifyOptions libtorch;
  libtorch.runtimes = {Runtime::LibTorch};
  EXPECT_THROW(verify_exports({c}, libtorch), Error);
  EXPECT_THROW(runtime_from_name("onnx-runtime"), Error);
  EXPECT_EQ(runtime_from_name("opencv-dnn"), Runtime::OpenCvDnn);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace cgsr
