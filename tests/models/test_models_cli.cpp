// The models through the real cgsr executable: info --model (names, spec files, model files),
// spec errors with file:line:col, bench.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "models/model_file.h"
#include "tests/support/cli_runner.h"

using cgsr::test::run_cgsr;
using cgsr::test::scratch_dir;

TEST(ModelsCli, InfoCountsParametersAndMacs) {
  const auto r = run_cgsr("info --model pan --scale 2 --input 640x360 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j.contains("system"));
  const auto& c = j["model"]["complexity"];
  EXPECT_EQ(c["params"].get<int64_t>(), 261403);
  EXPECT_EQ(c["output"].get<std::string>(), "1280x720");
  EXPECT_NEAR(c["macs_g"].get<double>(), 70.52, 0.005);
  EXPECT_EQ(c["layers"][0]["name"].get<std::string>(), "backbone.conv_first");
}

TEST(ModelsCli, InfoTableDefaultsTo720pOutput) {
  const auto r = run_cgsr("info --model edsr --scale 3");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("426x240 -> output 1278x720"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("1,554,499"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("160.1G"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("backbone.blocks.15.conv2"), std::string::npos);
  EXPECT_NE(r.out.find("libtorch"), std::string::npos);  // the system part stays
}

TEST(ModelsCli, SpecTypoIsAnErrorWithFileLineColumn) {
  const auto dir = scratch_dir("models-cli-typo");
  const auto path = dir / "bad.yaml";
  cgsr::write_file_atomic(path, "backbone: pan\nscale: 2\nwidths:\n  featurs: 32\n");
  const auto r = run_cgsr("info --model " + path.string());
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.err.find(path.string() + ":4:3"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("did you mean 'features'"), std::string::npos) << r.err;
  std::filesystem::remove_all(dir);
}

TEST(ModelsCli, InfoReadsSpecAndModelFiles) {
  const auto dir = scratch_dir("models-cli-files");
  cgsr::write_file_atomic(dir / "small.yaml",
                          "backbone: pan\nscale: 4\nblocks: 4\nrit: {enabled: true, channels: [depth, edge]}\n"
                          "geometry: {enabled: true}\n");
  auto r = run_cgsr("info --json --model " + (dir / "small.yaml").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["model"]["source"].get<std::string>(), "spec file");
  EXPECT_EQ(j["model"]["channels"], nlohmann::json::array({"depth", "edge"}));
  EXPECT_GT(j["model"]["training_only_params"].get<int64_t>(), 0);

  cgsr::Provenance prov;
  prov.stage = "search";
  prov.metrics = {{"psnr", 35.5}};
  cgsr::SRNetwork net(cgsr::default_spec("srcnn", 3));
  cgsr::save_model(dir / "srcnn.cgsr", *net, prov);
  r = run_cgsr("info --json --model " + (dir / "srcnn.cgsr").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["model"]["source"].get<std::string>(), "model file");
  EXPECT_EQ(j["model"]["provenance"]["stage"].get<std::string>(), "search");
  EXPECT_EQ(j["model"]["complexity"]["params"].get<int64_t>(), 69251);
  // A scale that contradicts the file, a truncated file, an unknown name.
  EXPECT_EQ(run_cgsr("info --model " + (dir / "srcnn.cgsr").string() + " --scale 2").exit_code, 2);
  const std::string bytes = cgsr::read_file(dir / "srcnn.cgsr");
  cgsr::write_file_atomic(dir / "cut.cgsr", bytes.substr(0, bytes.size() - 100));
  r = run_cgsr("info --model " + (dir / "cut.cgsr").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("truncated"), std::string::npos) << r.err;
  r = run_cgsr("info --model edrs");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("did you mean 'edsr'"), std::string::npos) << r.err;
  std::filesystem::remove_all(dir);
}

TEST(ModelsCli, BenchReportsLatencyAndThroughput) {
  const auto r = run_cgsr("bench --model pan --input 24x16 --warmup 1 --runs 3 --threads 1 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["threads"].get<int>(), 1);
  const auto& row = j["results"][0];
  EXPECT_EQ(row["runtime"].get<std::string>(), "cgsr fused");  // the default engine
  EXPECT_GT(row["median_ms"].get<double>(), 0.0);
  EXPECT_LE(row["min_ms"].get<double>(), row["median_ms"].get<double>());
  EXPECT_GE(row["max_ms"].get<double>(), row["median_ms"].get<double>());
  EXPECT_GT(row["gflops"].get<double>(), 0.0);
  EXPECT_EQ(row["macs"].get<int64_t>(), (245880LL * 24 * 16) + 15048LL * 48 * 32);
  EXPECT_EQ(run_cgsr("bench --runs 2").exit_code, 2);  // nothing to time
}
