#pragma once
// The tiny procedural scene (configs/scenes/tiny.yaml: 6 frames, 64x48 and 128x96), rendered
// once per test process by the real cgsr binary.

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "render_data/dataset.h"
#include "tests/support/cli_runner.h"

namespace cgsr::test {

inline const std::filesystem::path& tiny_data() {
  static const std::filesystem::path dir = [] {
    const auto d = scratch_dir("tiny-data") / "data";
    const auto r = run_cgsr("render --config " + std::string(CGSR_SOURCE_DIR) + "/configs/scenes/tiny.yaml --out " +
                            d.string() + " --threads 1");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return d;
  }();
  return dir;
}

// The tiny scene twice as one data set: scene tiny_a (its 6 frames), then tiny_b, its camera walk
// spread over 24 frames so that most of a frame stays in view of the next; the cut is at frame 6.
// `extra` is appended to both scene configs (e.g. a jitter setting). Rendered once per test
// process for each `extra`, into a scratch directory named `name`.
inline std::filesystem::path two_scene_walk(const std::string& name, const std::string& extra = "") {
  static std::map<std::string, std::filesystem::path> rendered;
  if (const auto it = rendered.find(extra); it != rendered.end()) return it->second;
  const std::filesystem::path dir = scratch_dir(name);
  std::ostringstream text;
  text << std::ifstream(std::string(CGSR_SOURCE_DIR) + "/configs/scenes/tiny.yaml").rdbuf();
  std::string b = text.str() + extra;
  const auto at_name = b.find("name: tiny\nframes: 6");
  EXPECT_NE(at_name, std::string::npos);
  std::string a = b;
  a.replace(at_name, 20, "name: tiny_a\nframes: 6");
  b.replace(at_name, 20, "name: tiny_b\nframes: 24");
  std::ofstream(dir / "tiny_a.yaml") << a;
  std::ofstream(dir / "tiny_b.yaml") << b;
  const auto r = run_cgsr("render --scene " + (dir / "tiny_a.yaml").string() + " --scene " + (dir / "tiny_b.yaml").string() +
                          " --threads 1 --out " + (dir / "set").string());
  EXPECT_EQ(r.exit_code, 0) << r.all();
  return rendered[extra] = dir / "set";
}

// Opening options that load exactly these channels.
inline DatasetOpenOptions with_channels(std::vector<std::string> channels) {
  DatasetOpenOptions o;
  o.channels = std::move(channels);
  return o;
}

}  // namespace cgsr::test
