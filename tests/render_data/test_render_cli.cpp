// The real CLI: `cgsr render` on the tiny scene, `cgsr data check` on the result (clean, then
// with a corrupt and a missing file), resuming an interrupted render, and `cgsr data preview`.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <fstream>

#include "core/image_io.h"
#include "render_data/dataset_manifest.h"
#include "test_scenes.h"

namespace cgsr {
namespace {
namespace fs = std::filesystem;

struct CliRun {
  int code = -1;
  std::string output;
};

CliRun cgsr(const std::string& args) {
  const std::string command = std::string(CGSR_BINARY) + " " + args + " 2>&1";
  CliRun r;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf{};
  while (fgets(buf.data(), buf.size(), pipe)) r.output += buf.data();
  const int status = pclose(pipe);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

std::string tiny_config() { return std::string(CGSR_SOURCE_DIR) + "/configs/scenes/tiny.yaml"; }

TEST(RenderCli, RenderThenCheckThenResumeThenDetectDamage) {
  const fs::path out = test::temp_dir("cli_render") / "tiny";
  const CliRun render = cgsr("render --config " + tiny_config() + " --out " + out.string());
  ASSERT_EQ(render.code, 0) << render.output;
  EXPECT_NE(render.output.find("per frame"), std::string::npos) << render.output;
  const DatasetManifest m = read_manifest(out);
  EXPECT_TRUE(m.complete);
  EXPECT_EQ(m.frames, 6);
  ASSERT_EQ(m.resolutions.size(), 2u);
  EXPECT_TRUE(fs::exists(out / "config.yaml"));
  EXPECT_TRUE(fs::exists(out / "128x96" / "motion" / "000005.exr"));

  const CliRun check = cgsr("data check " + out.string());
  ASSERT_EQ(check.code, 0) << check.output;
  EXPECT_NE(check.output.find("problems     none"), std::string::npos) << check.output;
  EXPECT_NE(check.output.find("12 frame/resolution pairs"), std::string::npos) << check.output;

  // An interrupted render (a frame's file missing) resumes: only that frame is rendered again.
  fs::remove(out / "64x48" / "color" / "000002.png");
  const CliRun resume = cgsr("render --config " + tiny_config() + " --out " + out.string());
  ASSERT_EQ(resume.code, 0) << resume.output;
  EXPECT_NE(resume.output.find("rendered 1 frame(s) (5 resumed)"), std::string::npos) << resume.output;
  // A different configuration does not mix into the same directory.
  const CliRun other = cgsr("render --config " + tiny_config() + " --set frames=7 --out " + out.string());
  EXPECT_EQ(other.code, 2) << other.output;
  EXPECT_NE(other.output.find("different configuration"), std::string::npos) << other.output;

  // Damage: a corrupt depth file and a missing edge file are counted, named, and exit code 2.
  std::ofstream(out / "64x48" / "depth" / "000003.exr", std::ios::trunc) << "not an exr";
  fs::remove(out / "128x96" / "edge" / "000001.png");
  const CliRun damaged = cgsr("data check " + out.string());
  EXPECT_EQ(damaged.code, 2) << damaged.output;
  EXPECT_NE(damaged.output.find("64x48/depth/000003.exr: frame 3"), std::string::npos) << damaged.output;
  EXPECT_NE(damaged.output.find("128x96/edge/000001.png: frame 1: missing file"), std::string::npos) << damaged.output;
  EXPECT_NE(damaged.output.find("missing                1"), std::string::npos) << damaged.output;
  EXPECT_NE(damaged.output.find("unreadable             1"), std::string::npos) << damaged.output;
}

TEST(RenderCli, PreviewWritesAMontage) {
  const fs::path out = test::temp_dir("cli_preview") / "tiny";
  ASSERT_EQ(cgsr("render --config " + tiny_config() + " --set frames=2 --out " + out.string()).code, 0);
  const fs::path png = out.parent_path() / "preview.png";
  const CliRun preview = cgsr("data preview " + out.string() + " --frame 1 --image " + png.string());
  ASSERT_EQ(preview.code, 0) << preview.output;
  const auto image = read_image(png);
  EXPECT_EQ(image.size(2), 2 * 128 + 4);    // LR (enlarged) | HR
  EXPECT_EQ(image.size(1), 4 * 96 + 3 * 4);  // colour, depth, normal, edge rows
}

TEST(RenderCli, BadConfigsAreUserErrors) {
  const CliRun scale = cgsr("render --config " + tiny_config() + " --set resolutions=[64x48,100x75] --out " +
                         (test::temp_dir("cli_bad") / "x").string());
  EXPECT_EQ(scale.code, 2) << scale.output;
  EXPECT_NE(scale.output.find("not an integer scale"), std::string::npos) << scale.output;
  const CliRun missing = cgsr("data check " + (test::temp_dir("cli_bad2") / "nothing").string());
  EXPECT_EQ(missing.code, 2) << missing.output;
}

}  // namespace
}  // namespace cgsr
