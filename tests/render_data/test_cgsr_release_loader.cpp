// The CGSR data release layout on a fixture written here: <trace>/<width>/frame###.sim.ppm and
// feature###.bmp with periodic tile-grid lines in the edge channel.
#include <gtest/gtest.h>

#include <torch/torch.h>

#include <fstream>

#include "core/error.h"
#include "core/image_io.h"
#include "render_data/dataset.h"
#include "render_data/derive_channels.h"
#include "test_scenes.h"

namespace cgsr {
namespace {
namespace fs = std::filesystem;

// Frame f at width W (4:3): colour gradient, a near box on a far wall, grid lines every 8 px.
void write_release_frame(const fs::path& dir, int f, int W, bool grid) {
  const int H = W * 3 / 4, s = W / 32;
  auto color = torch::rand({3, H, W});
  auto depth = torch::full({H, W}, 0.8f);
  auto angle = torch::full({H, W}, 0.2f);
  auto edge = torch::zeros({H, W});
  const int x0 = (8 + f) * s, x1 = (20 + f) * s, y0 = 6 * s, y1 = 16 * s;
  depth.slice(0, y0, y1).slice(1, x0, x1).fill_(0.3f);
  angle.slice(0, y0, y1).slice(1, x0, x1).fill_(0.5f);
  edge.slice(0, y0, y1).slice(1, x0, x0 + 1).fill_(1);
  edge.slice(0, y0, y1).slice(1, x1 - 1, x1).fill_(1);
  edge.slice(0, y0, y0 + 1).slice(1, x0, x1).fill_(1);
  edge.slice(0, y1 - 1, y1).slice(1, x0, x1).fill_(1);
  depth.slice(0, 0, 2 * s).fill_(0);  // a UI bar: depth 0, normal angle 0
  angle.slice(0, 0, 2 * s).fill_(0);
  if (grid) {
    edge.slice(0, 4, H, 8).fill_(1);
    edge.slice(1, 4, W, 8).fill_(1);
  }
  char name[32];
  std::snprintf(name, sizeof name, "%03d", f);
  write_image(dir / ("frame" + std::string(name) + ".sim.ppm"), color);
  write_image(dir / ("feature" + std::string(name) + ".bmp"), torch::stack({edge, depth, angle}));
}

fs::path write_release(const std::string& name, int frames, bool grid = true) {
  const fs::path root = test::scratch_dir(name) / "doom3";
  for (int W : {64, 128}) {
    fs::create_directories(root / std::to_string(W));
    for (int f = 0; f < frames; ++f) write_release_frame(root / std::to_string(W), f, W, grid);
  }
  return root;
}

TEST(CgsrReleaseLoader, LoadsTheLayoutWithoutCleanup) {
  const fs::path root = write_release("release_plain", 10);
  const Dataset data = Dataset::open(root);
  EXPECT_EQ(data.info().layout, "cgsr-release");
  EXPECT_EQ(data.frame_count(), 10);
  ASSERT_EQ(data.resolutions().size(), 2u);
  EXPECT_EQ(data.resolutions()[0], (Resolution{64, 48}));
  EXPECT_EQ(data.resolutions()[1], (Resolution{128, 96}));
  EXPECT_EQ(data.info().split.test.size(), 1u);
  EXPECT_EQ(data.info().split.val.size(), 2u);
  const auto f = data.frame(3, 1);
  EXPECT_TRUE(f->has(RenderChannel::Edge) && f->has(RenderChannel::Depth) && f->has(RenderChannel::NormalAngle));
  EXPECT_FALSE(f->has(RenderChannel::Normal));
  // Without cleanup the grid lines are still in the edges.
  EXPECT_EQ(f->edge[0][4].sum().item<int64_t>(), 128);
  // Depth round trip: normalize_depth with the dataset's planes gives the stored values back.
  const auto nd = normalize_depth(f->depth, data.info().near_plane, data.info().far_plane);
  EXPECT_NEAR(nd[0][50][2].item<float>(), std::round(0.8f * 255) / 255, 1e-5f);
  EXPECT_NEAR(nd[0][0][0].item<float>(), 0.0f, 1e-6f);  // UI region
  EXPECT_NEAR(f->normal_angle[0][50][2].item<float>(), std::round(0.2f * 255) / 255, 1e-3f);
}

TEST(CgsrReleaseLoader, GridCleanupRemovesTheLinesAndKeepsTheBox) {
  const fs::path root = write_release("release_clean", 4);
  DatasetOpenOptions o;
  o.clean_grid_lines = true;
  const Dataset data = Dataset::open(root, o);
  const auto f = data.frame(1, 1);
  const auto e = f->edge[0];
  // Row 4 only keeps edge pixels where the box edges cross it (none: the box starts at row 24).
  EXPECT_EQ(e[4].sum().item<int64_t>(), 0);
  EXPECT_EQ(e.select(1, 4).sum().item<int64_t>(), 0);
  // The box outline (rows 24..63, columns 36..83 at 128 wide) is intact off the grid lines.
  // Its top edge crosses grid columns 44..76 (kept: a real crossing); only the corner at grid
  // column 36, with nothing to its left, goes.
  EXPECT_EQ(e[24].slice(0, 36, 84).sum().item<int64_t>(), 47);
  EXPECT_EQ(e[40][83].item<uint8_t>(), 1);  // the right side, off the grid columns
  // And the clean-up is reported.
  EXPECT_FALSE(data.info().notes.empty());
}

TEST(CgsrReleaseLoader, DerivedNormalsAreReported) {
  const fs::path root = write_release("release_derive", 3, false);
  DatasetOpenOptions o;
  o.derive = {"normal"};
  const Dataset data = Dataset::open(root, o);
  ASSERT_EQ(data.info().derived.size(), 1u);
  EXPECT_EQ(data.info().derived[0], RenderChannel::Normal);
  const auto f = data.frame(0, 0);
  ASSERT_TRUE(f->has(RenderChannel::Normal));
  // Asking for a channel that is neither stored nor derivable is an error that says so.
  DatasetOpenOptions bad;
  bad.channels = {"motion"};
  try {
    Dataset::open(root, bad);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no 'motion' channel"), std::string::npos) << e.what();
  }
}

TEST(CgsrReleaseLoader, MissingAndCorruptFilesAreNamed) {
  const fs::path root = write_release("release_bad", 3);
  fs::remove(root / "128" / "feature001.bmp");
  try {
    Dataset::open(root);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("128/feature001.bmp"), std::string::npos) << e.what();
  }
  write_release_frame(root / "128", 1, 128, true);
  std::ofstream(root / "64" / "feature002.bmp", std::ios::trunc) << "not an image";
  const Dataset data = Dataset::open(root);
  try {
    data.frame(2, 0);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("64/feature002.bmp"), std::string::npos) << what;
    EXPECT_NE(what.find("frame 2"), std::string::npos) << what;
  }
}

TEST(CgsrReleaseLoader, NonIntegerScaleIsRejected) {
  const fs::path root = write_release("release_scale", 2);
  fs::create_directories(root / "96");
  for (int f = 0; f < 2; ++f) write_release_frame(root / "96", f, 96, false);
  // 96x72 vs 64x48 is a 1.5x scale.
  try {
    Dataset::open(root);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("not an integer scale"), std::string::npos) << e.what();
  }
}

// The size of a width folder comes from its first colour file's header, never from decoding it:
// a PPM that declares 64x100000 is refused, and so is a feature file declaring another size.
TEST(CgsrReleaseLoader, HeadersDeclaringHugeOrWrongSizesAreRefusedBeforeDecoding) {
  const fs::path root = write_release("release_bomb", 2);
  const fs::path first = root / "64" / "frame000.sim.ppm";
  std::ofstream(first, std::ios::binary | std::ios::trunc) << "P6\n64 100000\n255\n" << std::string(64 * 3, '\0');
  try {
    Dataset::open(root);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(first.string() + ": the PNM header declares 64x100000 pixels, beyond the limit"),
              std::string::npos)
        << e.what();
  }
  write_release_frame(root / "64", 0, 64, true);
  const fs::path feature = root / "64" / "feature001.bmp";
  write_image(feature, torch::rand({3, 480, 640}));
  const Dataset data = Dataset::open(root);
  try {
    data.frame(1, 0);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(feature.string() + ": frame 1: size 640x480 (from the BMP header; not "
                                                              "decoded) does not match the resolution 64x48"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace cgsr
