// The real CLI: `cgsr render` on the tiny scene, `cgsr data check` on the result (clean, then
// with a corrupt and a missing file), resuming an interrupted render, and `cgsr data preview`.
#include <gtest/gtest.h>

#include <fstream>

#include <nlohmann/json.hpp>

#include "core/image_io.h"
#include "render_data/dataset_manifest.h"
#include "test_scenes.h"
#include "tests/support/cli_runner.h"

namespace cgsr {
namespace {
namespace fs = std::filesystem;

using test::CliResult;
using test::run_cgsr;

// fuzz/corpus's bomb seed without its file-kind byte.
fs::path bomb_png() {
  const fs::path path = test::scratch_dir("bomb") / "bomb.png";
  std::ifstream in(std::string(CGSR_SOURCE_DIR) + "/fuzz/corpus/frame_files/color_bomb_20000x20000.bin", std::ios::binary);
  in.get();
  std::ofstream(path, std::ios::binary) << in.rdbuf();
  return path;
}

std::string tiny_config() { return std::string(CGSR_SOURCE_DIR) + "/configs/scenes/tiny.yaml"; }

TEST(RenderCli, RenderThenCheckThenResumeThenDetectDamage) {
  const fs::path out = test::scratch_dir("cli_render") / "tiny";
  const CliResult render = run_cgsr("render --config " + tiny_config() + " --out " + out.string());
  ASSERT_EQ(render.exit_code, 0) << render.all();
  EXPECT_NE(render.all().find("per frame"), std::string::npos) << render.all();
  const DatasetManifest m = read_manifest(out);
  EXPECT_TRUE(m.complete);
  EXPECT_EQ(m.frames, 6);
  ASSERT_EQ(m.resolutions.size(), 2u);
  EXPECT_TRUE(fs::exists(out / "config.yaml"));
  EXPECT_TRUE(fs::exists(out / "128x96" / "motion" / "000005.exr"));
  // Motion rejected behind the previous camera is reported per resolution over the rendered frames.
  const auto results = nlohmann::json::parse(std::ifstream(out / "results.json"));
  const auto& rejected = results.at("motion_rejected");
  EXPECT_EQ(rejected.at("frames_counted"), 6);
  for (const char* r : {"64x48", "128x96"}) {
    EXPECT_GE(rejected.at(r).at("pixels").get<int64_t>(), rejected.at(r).at("max_per_frame").get<int64_t>()) << r;
    EXPECT_LE(rejected.at(r).at("frames").get<int>(), 6) << r;
  }

  const CliResult check = run_cgsr("data check " + out.string());
  ASSERT_EQ(check.exit_code, 0) << check.all();
  EXPECT_NE(check.all().find("problems     none"), std::string::npos) << check.all();
  EXPECT_NE(check.all().find("12 frame/resolution pairs"), std::string::npos) << check.all();

  // An interrupted render (a frame's file missing) resumes: only that frame is rendered again.
  fs::remove(out / "64x48" / "color" / "000002.png");
  const CliResult resume = run_cgsr("render --config " + tiny_config() + " --out " + out.string());
  ASSERT_EQ(resume.exit_code, 0) << resume.all();
  EXPECT_NE(resume.all().find("rendered 1 frame(s) (5 resumed)"), std::string::npos) << resume.all();
  // A different configuration does not mix into the same directory.
  const CliResult other = run_cgsr("render --config " + tiny_config() + " --set frames=7 --out " + out.string());
  EXPECT_EQ(other.exit_code, 2) << other.all();
  EXPECT_NE(other.all().find("different configuration"), std::string::npos) << other.all();

  // Damage: a corrupt depth file and a missing edge file are counted, named, and exit code 2.
  std::ofstream(out / "64x48" / "depth" / "000003.exr", std::ios::trunc) << "not an exr";
  fs::remove(out / "128x96" / "edge" / "000001.png");
  // A decompression bomb as a colour frame (1 KB declaring 20000x20000): named, never decoded.
  fs::copy_file(bomb_png(), out / "64x48" / "color" / "000004.png", fs::copy_options::overwrite_existing);
  const CliResult damaged = run_cgsr("data check " + out.string());
  EXPECT_NE(damaged.all().find("64x48/color/000004.png: frame 4: size 20000x20000 (from the PNG header; not decoded) "
                               "does not match the resolution 64x48"),
            std::string::npos)
      << damaged.all();
  EXPECT_NE(damaged.all().find("wrong size             1"), std::string::npos) << damaged.all();
  EXPECT_EQ(damaged.exit_code, 2) << damaged.all();
  EXPECT_NE(damaged.all().find("64x48/depth/000003.exr: frame 3"), std::string::npos) << damaged.all();
  EXPECT_NE(damaged.all().find("128x96/edge/000001.png: frame 1: missing file"), std::string::npos) << damaged.all();
  EXPECT_NE(damaged.all().find("missing                1"), std::string::npos) << damaged.all();
  EXPECT_NE(damaged.all().find("unreadable             1"), std::string::npos) << damaged.all();
}

// The manifest says complete only once everything after the frames is written: a render whose
// results.json cannot be written (a full disk, injected) exits 2 with the manifest incomplete,
// and the rerun finishes it from the frames on disk.
TEST(RenderCli, TheManifestIsMarkedCompleteOnlyAfterTheResults) {
  const fs::path out = test::scratch_dir("cli_render_results") / "tiny";
  const std::string args = "render --config " + tiny_config() + " --set frames=2 --out " + out.string();
  ::setenv("CGSR_FAULT_NO_SPACE", "results.json", 1);
  const CliResult full = run_cgsr(args);
  ::unsetenv("CGSR_FAULT_NO_SPACE");
  EXPECT_EQ(full.exit_code, 2) << full.all();
  EXPECT_NE(full.all().find("results.json"), std::string::npos) << full.all();
  EXPECT_FALSE(fs::exists(out / "results.json"));
  EXPECT_FALSE(read_manifest(out).complete);

  const CliResult rerun = run_cgsr(args);
  ASSERT_EQ(rerun.exit_code, 0) << rerun.all();
  EXPECT_NE(rerun.all().find("rendered 0 frame(s) (2 resumed)"), std::string::npos) << rerun.all();
  EXPECT_TRUE(fs::exists(out / "results.json"));
  EXPECT_TRUE(read_manifest(out).complete);
}

TEST(RenderCli, PreviewWritesAMontage) {
  const fs::path out = test::scratch_dir("cli_preview") / "tiny";
  ASSERT_EQ(run_cgsr("render --config " + tiny_config() + " --set frames=2 --out " + out.string()).exit_code, 0);
  const fs::path png = out.parent_path() / "preview.png";
  const CliResult preview = run_cgsr("data preview " + out.string() + " --frame 1 --image " + png.string());
  ASSERT_EQ(preview.exit_code, 0) << preview.all();
  const auto image = read_image(png);
  EXPECT_EQ(image.size(2), 2 * 128 + 4);    // LR (enlarged) | HR
  EXPECT_EQ(image.size(1), 4 * 96 + 3 * 4);  // colour, depth, normal, edge rows
}

TEST(RenderCli, BadConfigsAreUserErrors) {
  const CliResult scale = run_cgsr("render --config " + tiny_config() + " --set resolutions=[64x48,100x75] --out " +
                         (test::scratch_dir("cli_bad") / "x").string());
  EXPECT_EQ(scale.exit_code, 2) << scale.all();
  EXPECT_NE(scale.all().find("not an integer scale"), std::string::npos) << scale.all();
  const CliResult missing = run_cgsr("data check " + (test::scratch_dir("cli_bad2") / "nothing").string());
  EXPECT_EQ(missing.exit_code, 2) << missing.all();
}

}  // namespace
}  // namespace cgsr
