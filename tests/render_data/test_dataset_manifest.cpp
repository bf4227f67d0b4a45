// The dataset manifest: round trip, split proportions, malformed manifests.
#include <gtest/gtest.h>

#include <fstream>
#include <set>

#include "core/error.h"
#include "render_data/dataset_manifest.h"
#include "test_scenes.h"

namespace cgsr {
namespace {
namespace fs = std::filesystem;

TEST(DatasetManifest, RoundTrip) {
  const fs::path dir = test::scratch_dir("manifest_round_trip");
  DatasetManifest m;
  m.name = "room";
  m.complete = true;
  m.fingerprint = "0123456789abcdef";
  m.frames = 50;
  m.resolutions = {{320, 240}, {640, 480}, {1280, 960}};
  m.near_plane = 1e-3;
  m.far_plane = 1e6;
  m.vfov = 72.5;
  m.scene_source = "procedural";
  m.seed = 42;
  m.split = make_split(50);
  m.bytes_per_frame = {1000, 4000, 16000};
  write_manifest(dir, m);
  const DatasetManifest r = read_manifest(dir);
  EXPECT_EQ(r.name, m.name);
  EXPECT_EQ(r.complete, true);
  EXPECT_EQ(r.fingerprint, m.fingerprint);
  EXPECT_EQ(r.frames, 50);
  ASSERT_EQ(r.resolutions.size(), 3u);
  EXPECT_EQ(r.resolutions[2], (Resolution{1280, 960}));
  EXPECT_DOUBLE_EQ(r.near_plane, 1e-3);
  EXPECT_DOUBLE_EQ(r.far_plane, 1e6);
  EXPECT_DOUBLE_EQ(r.vfov, 72.5);
  EXPECT_EQ(r.seed, 42u);
  EXPECT_EQ(r.split.train, m.split.train);
  EXPECT_EQ(r.split.val, m.split.val);
  EXPECT_EQ(r.split.test, m.split.test);
  EXPECT_EQ(r.bytes_per_frame, m.bytes_per_frame);
  EXPECT_EQ(frame_file(dir, {320, 240}, FileKind::Depth, 7), dir / "320x240" / "depth" / "000007.exr");
}

TEST(DatasetManifest, SplitProportionsAndUniformTestFrames) {
  for (int n : {3, 10, 57, 300, 1001}) {
    SCOPED_TRACE(n);
    const FrameSplit s = make_split(n);
    EXPECT_EQ(static_cast<int>(s.train.size() + s.val.size() + s.test.size()), n);
    std::set<int> all(s.train.begin(), s.train.end());
    all.insert(s.val.begin(), s.val.end());
    all.insert(s.test.begin(), s.test.end());
    EXPECT_EQ(static_cast<int>(all.size()), n);  // disjoint and complete
    EXPECT_NEAR(static_cast<double>(s.test.size()) / n, 0.1, 0.5 / n + 0.1 * (n < 10));
    EXPECT_NEAR(static_cast<double>(s.val.size()) / n, 0.2, 0.5 / n + 0.2 * (n < 10));
    // Test frames spread over the whole sequence: gaps between them are all about n / n_test.
    if (s.test.size() >= 2) {
      const double gap = static_cast<double>(n) / s.test.size();
      for (size_t k = 1; k < s.test.size(); ++k) EXPECT_NEAR(s.test[k] - s.test[k - 1], gap, 1.0);
      EXPECT_LT(s.test.front(), gap);
      EXPECT_GT(s.test.back(), n - 1 - gap);
    }
  }
  EXPECT_EQ(make_split(300).test.size(), 30u);
  EXPECT_EQ(make_split(300).val.size(), 60u);
  EXPECT_EQ(make_split(300).train.size(), 210u);
  EXPECT_EQ(make_split(2).train.size(), 2u);
  // Deterministic.
  EXPECT_EQ(make_split(123).val, make_split(123).val);
}

TEST(DatasetManifest, MalformedManifestsNameFileAndKey) {
  const fs::path dir = test::scratch_dir("manifest_bad");
  EXPECT_THROW(read_manifest(dir), Error);
  std::ofstream(dir / "manifest.yaml") << "format: cgsr-dataset\nversion: 1\nname: x\ncomplete: true\nfingerprint: a\n"
                                          "frames: 4\nresolutions: [320x240, 500x480]\nnear: 0.1\nfar: 0.05\n"
                                          "split: {train: [0, 1], val: [2], test: [3]}\n";
  try {
    read_manifest(dir);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("manifest.yaml:9"), std::string::npos) << what;
    EXPECT_NE(what.find("near < far"), std::string::npos) << what;
  }
  std::ofstream(dir / "manifest.yaml", std::ios::trunc)
      << "format: cgsr-dataset\nversion: 1\nname: x\ncomplete: true\nfingerprint: a\n"
         "frames: 4\nresolutions: [320x240]\nnear: 0.1\nfar: 10\nsplit: {train: [0, 1, 7], val: [2], test: [3]}\n";
  try {
    read_manifest(dir);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("split.train: frame '7' is out of range [0, 3]"), std::string::npos) << e.what();
  }
  std::ofstream(dir / "manifest.yaml", std::ios::trunc)
      << "format: cgsr-dataset\nversion: 1\nname: x\ncomplete: true\nfingerprint: a\n"
         "frames: 0\nresolutions: [320x240]\nnear: 0.1\nfar: 10\nsplit: {train: [], val: [], test: []}\n";
  try {
    read_manifest(dir);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("manifest.yaml:6:9: frames: '0' is out of range [1, inf)"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace cgsr
