// Every network exports in both formats and runs in every runtime (ONNX Runtime, OpenCV DNN,
// LibTorch, Python torch) within 1e-4 of our own forward pass.

#include <gtest/gtest.h>

#include <torch/torch.h>

#include <map>

#include "export/exporter.h"
#include "export/verification.h"
#include "tests/export/export_cases.h"
#include "tests/support/cli_runner.h"

namespace cgsr {
namespace {

constexpr int64_t kWidth = 12, kHeight = 10;

struct Exported {
  test::ExportCase c;
  SRNetwork net{nullptr};
};

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
  // Each case ran in both runtimes of its format: nothing skipped, nothing failed.
  std::map<std::string, int> ran;
  for (const auto& check : report.checks) {
    SCOPED_TRACE(check.label + " in " + runtime_name(check.runtime));
    EXPECT_TRUE(check.skipped.empty()) << check.skipped;
    EXPECT_TRUE(check.error.empty()) << check.error;
    EXPECT_TRUE(check.ran);
    EXPECT_LE(check.max_abs_error, 1e-4);
    EXPECT_GE(check.max_abs_error, 0.0);
    ++ran[runtime_name(check.runtime)];
  }
  const int n = static_cast<int>(test::export_cases().size());
  EXPECT_EQ(ran["onnxruntime"], n);
  EXPECT_EQ(ran["opencv-dnn"], n);
  EXPECT_EQ(ran["libtorch"], n);
  EXPECT_EQ(ran["python-torch"], n);
  EXPECT_TRUE(report.ok()) << report.table();
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace cgsr
