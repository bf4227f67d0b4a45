// The runtime runners: raw tensor files, subprocesses, the job plumbing they share, ONNX Runtime through node, OpenCV DNN's
// fixed-size rule, and their errors.

#include <gtest/gtest.h>

#include <torch/torch.h>

#include "core/atomic_file.h"
#include "core/error.h"
#include "export/exporter.h"
#include "export/external_runner.h"
#include "export/onnxruntime_runner.h"
#include "export/opencv_runner.h"
#include "export/raw_tensor.h"
#include "export/subprocess.h"
#include "models/inference.h"
#include "tests/export/export_cases.h"
#include "tests/support/cli_runner.h"

namespace cgsr {
namespace {

TEST(RawTensor, RoundTripsAndRejectsTheWrongSize) {
  TempDir dir("raw-tensor-test");
  const auto t = torch::randn({2, 3, 4, 5});
  write_raw_float32(dir.path() / "t.f32", t);
  EXPECT_EQ(std::filesystem::file_size(dir.path() / "t.f32"), 2u * 3 * 4 * 5 * 4);
  EXPECT_TRUE(torch::equal(read_raw_float32(dir.path() / "t.f32", {2, 3, 4, 5}), t));
  EXPECT_THROW(read_raw_float32(dir.path() / "t.f32", {2, 3, 4, 6}), Error);
}

TEST(Subprocess, CapturesExitCodeAndOutputs) {
  const auto r = run_process({"sh", "-c", "echo out; echo err >&2; exit 3"});
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_EQ(r.out, "out\n");
  EXPECT_EQ(r.err, "err\n");
  EXPECT_THROW(run_process({"cgsr-no-such-program"}), Error);
  std::filesystem::path kept;
  {
    TempDir dir("temp-dir-test");
    kept = dir.path();
    write_file_atomic(dir.path() / "x", "1");
    EXPECT_TRUE(std::filesystem::exists(kept));
  }
  EXPECT_FALSE(std::filesystem::exists(kept));
}

// The runners' shared plumbing, with sh standing in for node or python3 (it is handed
// job.json and result.json as $1 and $2).
TEST(ExternalJob, WritesInputsRunsTheProgramAndReadsItsResult) {
  const ExternalJob job("Test runtime", "external-job-test");
  const auto t = torch::rand({1, 2, 3, 4});
  nlohmann::ordered_json spec;
  spec["inputs"] = job.write_inputs({{"x", t}}, "m0_r0");
  const auto echoed = job.run(spec, {"sh", "-c", "cp \"$1\" \"$2\"", "sh"});
  ASSERT_EQ(echoed["inputs"].size(), 1u);
  EXPECT_EQ(echoed["inputs"][0]["name"], "x");
  EXPECT_EQ(echoed["inputs"][0]["shape"], nlohmann::json({1, 2, 3, 4}));
  EXPECT_TRUE(torch::equal(read_raw_float32(echoed["inputs"][0]["file"].get<std::string>(), {1, 2, 3, 4}), t));
}

TEST(ExternalJob, AFailedOrUnreadableRunIsAnErrorNamingTheRuntime) {
  const ExternalJob job("Test runtime", "external-job-test");
  const auto message = [&](const std::vector<std::string>& program) {
    try {
      job.run(nlohmann::ordered_json::object(), program);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message({"sh", "-c", "echo broken >&2; exit 4", "sh"}).find("Test runtime"), std::string::npos);
  EXPECT_NE(message({"sh", "-c", "echo broken >&2; exit 4", "sh"}).find("exit 4"), std::string::npos);
  EXPECT_NE(message({"sh", "-c", "true", "sh"}).find("the runner failed"), std::string::npos);  // no result
  EXPECT_NE(message({"sh", "-c", "echo '{not json' > \"$2\"", "sh"}).find("unreadable runner result"),
            std::string::npos);
}

TEST(OnnxRuntimeRunner, TimesRepeatedRunsAndReportsAModelItCannotLoadByName) {
  TempDir dir("ort-runner-test");
  SRNetwork net = test::build_network(test::shrunk_pan(2), 1);
  ExportOptions o;
  o.width = 9;
  o.height = 7;
  const auto good = export_network(*net, dir.path() / "good.onnx", o);
  write_file_atomic(dir.path() / "bad.onnx", "garbage");
  const auto color = torch::rand({1, 3, 7, 9});
  const OnnxRuntimeRunner runner(1);
  const auto results = runner.run({{good.file, {{{{"lr_color", color}}, /*warmup=*/1, /*repeats=*/3}}},
                                   {dir.path() / "bad.onnx", {{{{"lr_color", color}}, 0, 1}}}});
  ASSERT_EQ(results.size(), 2u);
  ASSERT_TRUE(results[0].error.empty()) << results[0].error;
  ASSERT_EQ(results[0].runs.size(), 1u);
  EXPECT_EQ(results[0].runs[0].times_ms.size(), 3u);
  for (double ms : results[0].runs[0].times_ms) EXPECT_GT(ms, 0.0);
  const torch::Tensor sr = find_tensor(results[0].runs[0].outputs, "sr");
  ASSERT_TRUE(sr.defined());
  EXPECT_LT((sr - infer(*net, color)).abs().max().item<double>(), 1e-4);
  EXPECT_FALSE(results[1].error.empty());
  EXPECT_FALSE(runner.version().empty());
  // run_checked turns the bad model into an error naming it; that call also shows an input of
  // the wrong size is ONNX Runtime's error, not a crash.
  try {
    runner.run_checked({{dir.path() / "bad.onnx", {{{{"lr_color", color}}, 0, 1}}}});
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.onnx"), std::string::npos) << e.what();
  }
}

TEST(OpenCvRunner, RunsFixedSizeFilesOnlyAndOnlyAtTheirSize) {
  TempDir dir("opencv-runner-test");
  SRNetwork net = test::build_network(test::shrunk_edsr(3), 2);
  ExportOptions o;
  o.width = 9;
  o.height = 7;
  const auto fixed = export_network(*net, dir.path() / "fixed.onnx", o);
  const auto color = torch::rand({1, 3, 7, 9});
  const auto out = find_tensor(run_opencv_dnn(fixed.file, {{"lr_color", color}}), "sr");
  EXPECT_LT((out - infer(*net, color)).abs().max().item<double>(), 1e-4);
  EXPECT_TRUE(opencv_dnn_unsupported_reason(fixed.file).empty());
  try {
    run_opencv_dnn(fixed.file, {{"lr_color", torch::rand({1, 3, 8, 9})}});
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("as written in the file"), std::string::npos) << e.what();
  }
  o.dynamic_size = true;
  const auto dynamic = export_network(*net, dir.path() / "dynamic.onnx", o);
  EXPECT_FALSE(opencv_dnn_unsupported_reason(dynamic.file).empty());
  try {
    run_opencv_dnn(dynamic.file, {{"lr_color", color}});
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("fixed-size exports only"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace cgsr
