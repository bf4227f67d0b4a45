#pragma once
// The tiny procedural scene (configs/scenes/tiny.yaml: 6 frames, 64x48 and 128x96), rendered
// once per test process by the real cgsr binary.

#include <filesystem>
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

// Opening options that load exactly these channels.
inline DatasetOpenOptions with_channels(std::vector<std::string> channels) {
  DatasetOpenOptions o;
  o.channels = std::move(channels);
  return o;
}

}  // namespace cgsr::test
