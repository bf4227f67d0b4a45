// The generic glob layout: a capture with only LR colour, 8-bit depth and motion plus HR
// colour; missing channels derived and reported.
#include <gtest/gtest.h>

#include <torch/torch.h>

#include <fstream>
#include <sstream>

#include "core/error.h"
#include "core/image_io.h"
#include "render_data/dataset.h"
#include "render_data/glob_layout.h"
#include "test_scenes.h"

namespace cgsr {
namespace {
namespace fs = std::filesystem;

fs::path write_capture(const std::string& name, int frames) {
  const fs::path root = test::scratch_dir(name);
  fs::create_directories(root / "lr");
  fs::create_directories(root / "hr");
  for (int f = 0; f < frames; ++f) {
    const std::string n = std::to_string(f);  // unpadded: natural order must sort 2 before 10
    write_image(root / "lr" / ("color_" + n + ".png"), torch::rand({3, 24, 32}));
    auto depth = torch::full({1, 24, 32}, 0.9f);
    depth.slice(2, 10, 20).fill_(0.5f);
    write_image(root / "lr" / ("depth_" + n + ".png"), depth);
    auto motion = torch::zeros({3, 24, 32});
    motion[0].fill_(1.5f + f);
    write_image(root / "lr" / ("mv_" + n + ".exr"), motion, {32});
    write_image(root / "hr" / ("frame" + n + ".png"), torch::rand({3, 48, 64}));
  }
  std::ofstream(root / "dataset.yaml") << "layout: glob\n"
                                          "name: capture\n"
                                          "near: 0.5\n"
                                          "far: 200\n"
                                          "vfov: 50\n"
                                          "resolutions:\n"
                                          "  - size: 32x24\n"
                                          "    color: lr/color_*.png\n"
                                          "    depth: lr/depth_*.png\n"
                                          "    motion: lr/mv_*.exr\n"
                                          "  - size: 64x48\n"
                                          "    color: hr/frame*.png\n";
  return root;
}

TEST(GlobLayout, NaturalOrder) {
  EXPECT_TRUE(natural_less("f2.png", "f10.png"));
  EXPECT_FALSE(natural_less("f10.png", "f2.png"));
  EXPECT_TRUE(natural_less("f002.png", "f10.png"));
  EXPECT_TRUE(natural_less("a.png", "b.png"));
}

TEST(GlobLayout, LoadsPartialCapturesAndDerivesOnRequest) {
  const fs::path root = write_capture("glob_capture", 12);
  DatasetOpenOptions o;
  o.derive = {"edge", "normal"};
  o.channels = {"depth", "normal", "edge", "motion"};
  const Dataset data = Dataset::open(root, o);
  EXPECT_EQ(data.info().layout, "glob");
  EXPECT_EQ(data.info().name, "capture");
  EXPECT_EQ(data.frame_count(), 12);
  EXPECT_EQ(data.info().derived, (std::vector<RenderChannel>{RenderChannel::Normal, RenderChannel::Edge}));
  // Frame 10 is the file "_10", not the second file in text order.
  const auto f = data.frame(10, 0);
  EXPECT_FLOAT_EQ(f->motion[0][3][3].item<float>(), 11.5f);
  EXPECT_TRUE(f->has(RenderChannel::Edge) && f->has(RenderChannel::Normal));
  // The depth step at column 10 shows up in the derived edges.
  EXPECT_GT(f->edge.select(2, 10).sum().item<int64_t>() + f->edge.select(2, 9).sum().item<int64_t>(), 20);
  // HR has only colour, and says so.
  const auto hr = data.frame(0, 1);
  EXPECT_FALSE(hr->has(RenderChannel::Depth));
  EXPECT_TRUE(channels_at(data.info(), 1).empty());
  EXPECT_EQ(channels_at(data.info(), 0).size(), 4u);
}

TEST(GlobLayout, MismatchedCountsNameThePatterns) {
  const fs::path root = write_capture("glob_counts", 4);
  fs::remove(root / "hr" / "frame3.png");
  try {
    Dataset::open(root);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("hr/frame*.png"), std::string::npos) << what;
    EXPECT_NE(what.find("matches 3 files"), std::string::npos) << what;
  }
}

// RGBA colour loads (alpha dropped by default); colour the contract cannot hold is an error that
// names the file and the frame.
TEST(GlobLayout, RgbaColourLoadsAndHdrColourIsRejectedByFileAndFrame) {
  const fs::path root = write_capture("glob_rgba", 3);
  const auto rgb = torch::rand({3, 24, 32});
  write_image(root / "lr" / "color_1.png", torch::cat({rgb, torch::full({1, 24, 32}, 0.5f)}, 0));
  const Dataset data = Dataset::open(root);
  EXPECT_TRUE(torch::equal(data.frame(1, 0)->color, (rgb * 255).round().to(torch::kUInt8)));
  write_image(root / "lr" / "color_2.exr", torch::full({3, 24, 32}, 3.0f), {32});
  fs::remove(root / "lr" / "color_2.png");
  std::stringstream text;
  text << std::ifstream(root / "dataset.yaml").rdbuf();
  std::string yaml = text.str();
  yaml.replace(yaml.find("lr/color_*.png"), 14, "lr/color_*.*");
  std::ofstream(root / "dataset.yaml") << yaml;
  try {
    Dataset::open(root).load(2, 0);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("color_2.exr"), std::string::npos) << what;
    EXPECT_NE(what.find("frame 2"), std::string::npos) << what;
    EXPECT_NE(what.find("display-referred"), std::string::npos) << what;
  }
}

// A '*' in the capture's own folder name is a name, not a wildcard (it used to be refused).
TEST(GlobLayout, ACaptureFolderNamedWithAStarLoads) {
  const fs::path root = write_capture("glob_star*[1]", 2);
  EXPECT_EQ(Dataset::open(root).frame_count(), 2);
  // A wildcard in the pattern's own folders is still refused.
  std::ofstream(root / "dataset.yaml") << "layout: glob\nresolutions:\n  - size: 32x24\n    color: l*/color_*.png\n";
  try {
    Dataset::open(root);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("l*/color_*.png: wildcards are only supported in the file name"),
              std::string::npos)
        << e.what();
  }
}

// A capture description with a YAML syntax error says where, not "not a dataset in any layout".
TEST(GlobLayout, ASyntaxErrorInTheCaptureYamlNamesItsLine) {
  const fs::path root = write_capture("glob_syntax", 1);
  std::ofstream(root / "dataset.yaml") << "layout: glob\nresolutions:\n  - size: [32x24\n    color: lr/color_*.png\n";
  try {
    Dataset::open(root);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_EQ(e.kind(), ErrorKind::User);
    EXPECT_EQ(what.find("not a dataset"), std::string::npos) << what;
    EXPECT_NE(what.find((root / "dataset.yaml").string() + ":"), std::string::npos) << what;
    EXPECT_NE(what.find("invalid YAML"), std::string::npos) << what;
  }
}

// A capture frame whose header declares far more pixels than its resolution is refused before it
// is decoded, naming the file and the frame (fuzz/corpus's bomb seed: 1 KB, 20000x20000).
TEST(GlobLayout, ADecompressionBombFrameIsRefusedNamingTheFile) {
  const fs::path root = write_capture("glob_bomb", 2);
  std::ifstream in(std::string(CGSR_SOURCE_DIR) + "/fuzz/corpus/frame_files/color_bomb_20000x20000.bin",
                   std::ios::binary);
  in.get();  // the seed's file-kind byte
  std::ofstream(root / "hr" / "frame1.png", std::ios::binary | std::ios::trunc) << in.rdbuf();
  const Dataset data = Dataset::open(root);
  try {
    data.frame(1, 1);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::User);
    EXPECT_NE(std::string(e.what()).find((root / "hr" / "frame1.png").string() +
                                         ": frame 1: size 20000x20000 (from the PNG header; not decoded) does "
                                         "not match the resolution 64x48"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace cgsr
