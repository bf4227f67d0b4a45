// `cgsr export` and `cgsr bench --onnx` through the real executable.

#include <gtest/gtest.h>

#include <torch/torch.h>

#include "core/atomic_file.h"
#include "export/onnx_writer.h"
#include "models/model_file.h"
#include "tests/export/export_cases.h"
#include "tests/support/cli_runner.h"
#include "tests/support/tiny_data.h"

namespace cgsr {
namespace {

TEST(ExportCommand, ExportsAModelFileAndVerifiesItInOnnxRuntimeAndOpenCv) {
  const auto dir = test::scratch_dir("export-cli-onnx");
  // A trained-looking CG-enhanced, shrunk network saved as a model file.
  SRNetwork net = test::build_network(test::with_rit(test::shrunk_pan(2), "hr_pooled", "concat", true), 1);
  save_model(dir / "model.cgsr", *net);
  const auto out = dir / "model.onnx";
  const auto r = test::run_cgsr("export --model " + (dir / "model.cgsr").string() +
                                " --format onnx --input 12x10 --verify --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NO_THROW(check_onnx_file(out));
  EXPECT_NE(r.out.find("hr_render_info [1, 6, 20, 24]"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("ONNX checker ok"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("2 passed, 0 failed, 0 skipped"), std::string::npos) << r.out;
  for (const char* runtime : {"onnxruntime", "opencv-dnn"}) EXPECT_NE(r.out.find(runtime), std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(ExportCommand, SizeFreeExportsVerifyAtTwoSizesAndSayWhyOpenCvIsSkipped) {
  const auto dir = test::scratch_dir("export-cli-dynamic");
  const auto onnx = test::run_cgsr("export --model edsr --scale 3 --format onnx --input 12x10 --dynamic-size --verify "
                                   "--out " + (dir / "edsr.onnx").string());
  ASSERT_EQ(onnx.exit_code, 0) << onnx.out << onnx.err;
  EXPECT_NE(onnx.out.find("2 passed, 0 failed, 2 skipped"), std::string::npos) << onnx.out;
  EXPECT_NE(onnx.out.find("skipped: OpenCV DNN 4.6 imports DepthToSpace"), std::string::npos) << onnx.out;
  EXPECT_NE(onnx.out.find("9x6"), std::string::npos) << onnx.out;  // the second size
  EXPECT_TRUE(inspect_onnx_file(dir / "edsr.onnx").dynamic());

  const auto ts = test::run_cgsr("export --model srcnn --scale 2 --format torchscript --input 12x10 --verify --out " +
                                 (dir / "srcnn.pt").string());
  ASSERT_EQ(ts.exit_code, 0) << ts.out << ts.err;
  EXPECT_NE(ts.out.find("4 passed, 0 failed, 0 skipped"), std::string::npos) << ts.out;
  for (const char* runtime : {"libtorch", "python-torch"}) EXPECT_NE(ts.out.find(runtime), std::string::npos);
  std::filesystem::remove_all(dir);
}

// CG-enhanced SRPO end to end: `cgsr train` adds the RIT at SRPO's LR and HR features and trains
// a step, `cgsr export --verify` writes it (GridSample, so opset 16) and checks it in ONNX
// Runtime; OpenCV DNN is skipped with the reason.
TEST(ExportCommand, CgEnhancedSrpoTrainsAStepThenExportsAndVerifiesInOnnxRuntime) {
  const auto dir = test::scratch_dir("export-cli-srpo");
  const auto config = dir / "train.yaml";
  write_file_atomic(config, "data: " + test::tiny_data().string() +
                         "\nmodel: srpo\nscale: 2\n"
                         "enhance: {enabled: true, rit: {channels: [depth, edge], source: hr_unshuffle+hr_fuse}}\n"
                         "schedule: {steps: 1, batch_size: 2, patch_size: 16, val_frames: 1, validate_every: 0}\n"
                         "loss: {image_norm: l1}\n");
  const auto run = dir / "run";
  const auto trained = test::run_cgsr("train --config " + config.string() + " --threads 1 --out " + run.string());
  ASSERT_EQ(trained.exit_code, 0) << trained.out << trained.err;
  const ModelFileContents model = read_model_file(run / "model.cgsr");
  EXPECT_EQ(model.spec.backbone, "srpo");
  EXPECT_TRUE(model.spec.rit.enabled);
  const auto out = dir / "srpo.onnx";
  const auto r = test::run_cgsr("export --model " + (run / "model.cgsr").string() +
                                " --format onnx --input 12x10 --verify --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("1 passed, 0 failed, 1 skipped"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("no GridSample layer"), std::string::npos) << r.out;
  const OnnxModelInfo info = inspect_onnx_file(out);
  EXPECT_EQ(info.opset, kOnnxGridSampleOpset);
  std::filesystem::remove_all(dir);
}

TEST(ExportCommand, BadArgumentsAreClearErrors) {
  const auto dir = test::scratch_dir("export-cli-errors");
  const auto out = " --out " + (dir / "x.onnx").string();
  const auto format = test::run_cgsr("export --model pan --format onnxx" + out);
  EXPECT_EQ(format.exit_code, 2);
  EXPECT_NE(format.err.find("did you mean 'onnx'"), std::string::npos) << format.err;
  const auto model = test::run_cgsr("export --model nosuchnet --format onnx" + out);
  EXPECT_EQ(model.exit_code, 2);
  EXPECT_NE(model.err.find("nosuchnet"), std::string::npos) << model.err;
  const auto dynamic = test::run_cgsr("export --model pan --format torchscript --dynamic-size" + out);
  EXPECT_EQ(dynamic.exit_code, 2);
  EXPECT_NE(dynamic.err.find("dynamic_size"), std::string::npos) << dynamic.err;
  const auto no_out = test::run_cgsr("export --model pan");
  EXPECT_EQ(no_out.exit_code, 2);
  EXPECT_NE(no_out.err.find("out"), std::string::npos) << no_out.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.onnx"));
  std::filesystem::remove_all(dir);
}

TEST(BenchCommand, TimesAnOnnxFileInOnnxRuntimeNextToOurForward) {
  const auto dir = test::scratch_dir("export-cli-bench");
  const auto file = (dir / "pan.onnx").string();
  ASSERT_EQ(test::run_cgsr("export --model pan --format onnx --input 12x10 --out " + file).exit_code, 0);
  // --onnx alone: our side is built from the spec the file records.
  const auto r = test::run_cgsr("bench --onnx " + file + " --input 12x10 --warmup 1 --runs 3 --json");
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["results"].size(), 2u);
  EXPECT_EQ(j["results"][0]["runtime"], "cgsr fused");  // the default engine
  EXPECT_EQ(j["results"][1]["runtime"], "onnxruntime");
  EXPECT_GT(j["results"][1]["median_ms"].get<double>(), 0.0);
  EXPECT_NEAR(j["onnxruntime_vs_cgsr"].get<double>(),
              j["results"][1]["median_ms"].get<double>() / j["results"][0]["median_ms"].get<double>(), 1e-9);
  const auto reference = test::run_cgsr("bench --onnx " + file + " --input 12x10 --engine libtorch --runs 1 --json");
  ASSERT_EQ(reference.exit_code, 0) << reference.err;
  EXPECT_EQ(nlohmann::json::parse(reference.out)["results"][0]["runtime"], "libtorch");
  // A fixed-size file timed at another size, or against another model, is refused clearly.
  const auto size = test::run_cgsr("bench --onnx " + file + " --input 16x16 --runs 1");
  EXPECT_EQ(size.exit_code, 2);
  EXPECT_NE(size.err.find("fixed at another size"), std::string::npos) << size.err;
  const auto other = test::run_cgsr("bench --model edsr --onnx " + file + " --input 12x10 --runs 1");
  EXPECT_EQ(other.exit_code, 2);
  EXPECT_NE(other.err.find("is an export of pan x2, not of edsr x2"), std::string::npos) << other.err;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace cgsr
