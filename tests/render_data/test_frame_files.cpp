// The per-frame files of the dataset format: exact round trips of extreme values, and bad
// files (corrupt, missing, NaN, zero-length normals, wrong size) named with their frame.
#include <gtest/gtest.h>

#include <torch/torch.h>

#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "core/error.h"
#include "core/image_io.h"
#include "render_data/dataset.h"
#include "render_data/frame_files.h"
#include "test_scenes.h"

namespace cgsr {
namespace {
namespace fs = std::filesystem;

void expect_error(const std::function<void()>& f, const std::vector<std::string>& parts) {
  try {
    f();
    ADD_FAILURE() << "expected an error";
  } catch (const Error& e) {
    for (const auto& p : parts) EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what();
  }
}

TEST(FrameFiles, ExtremeDepthsAndSkyRoundTripExactly) {
  const fs::path dir = test::scratch_dir("frame_files_extreme");
  GBuffer g = test::flat_gbuffer(8, 6);
  g.depth[0][0][0] = 1e-3f;
  g.depth[0][0][1] = 1e6f;
  g.depth[0][0][2] = 1.2345678f;
  g.depth[0][1].fill_(std::numeric_limits<float>::infinity());  // a row of sky
  g.normal.select(1, 1).zero_();
  g.motion[0][2][3] = -123.456f;
  g.motion[1][2][3] = 0.001f;
  g.edge.fill_(1.0f);  // every pixel an edge
  g.object_id[0][3][3] = 65000;
  const Resolution r{8, 6};
  write_frame_files(dir, r, 0, g);
  const auto depth = read_depth_file(frame_file(dir, r, FileKind::Depth, 0), 0, r);
  EXPECT_EQ(depth[0][0][0].item<float>(), 1e-3f);
  EXPECT_EQ(depth[0][0][1].item<float>(), 1e6f);
  EXPECT_EQ(depth[0][0][2].item<float>(), 1.2345678f);
  EXPECT_TRUE(torch::isinf(depth[0][1]).all().item<bool>());
  const auto normal = read_normal_file(frame_file(dir, r, FileKind::Normal, 0), 0, r, depth);
  EXPECT_EQ(normal.select(1, 1).abs().max().item<float>(), 0.0f);  // sky normals are exactly 0
  EXPECT_NEAR(normal[2][4][4].item<float>(), 1.0f, 1e-3f);
  const auto motion = read_motion_file(frame_file(dir, r, FileKind::Motion, 0), 0, r);
  EXPECT_EQ(motion[0][2][3].item<float>(), -123.456f);
  EXPECT_EQ(motion[1][2][3].item<float>(), 0.001f);
  EXPECT_EQ(read_edge_file(frame_file(dir, r, FileKind::Edge, 0), 0, r).sum().item<int64_t>(), 48);
  const auto ids = read_id_file(frame_file(dir, r, FileKind::Id, 0), 0, r);
  EXPECT_EQ(ids[0][3][3].item<int32_t>(), 65000);
  EXPECT_EQ(ids[1][3][3].item<int32_t>(), 0);
}

TEST(FrameFiles, BadFilesNameTheFileAndFrame) {
  const fs::path dir = test::scratch_dir("frame_files_bad");
  const Resolution r{8, 6};
  write_frame_files(dir, r, 4, test::flat_gbuffer(8, 6));
  const fs::path depth = frame_file(dir, r, FileKind::Depth, 4);
  // NaN and Inf in a depth file (write_image refuses them, so OpenCV writes this one directly;
  // image_io has already enabled its EXR codec above).
  cv::Mat bad(6, 8, CV_32FC1, cv::Scalar(2.0f));
  bad.at<float>(1, 1) = std::numeric_limits<float>::quiet_NaN();
  bad.at<float>(2, 2) = std::numeric_limits<float>::infinity();
  ASSERT_TRUE(cv::imwrite(depth.string(), bad));
  expect_error([&] { read_depth_file(depth, 4, r); }, {"depth/000004.exr", "frame 4", "1 NaN and 1 infinite"});
  write_frame_files(dir, r, 4, test::flat_gbuffer(8, 6));
  // Zero-length normals on geometry.
  write_image(frame_file(dir, r, FileKind::Normal, 4), torch::full({3, 6, 8}, 0.5f), {16});
  expect_error([&] { read_normal_file(frame_file(dir, r, FileKind::Normal, 4), 4, r, read_depth_file(depth, 4, r)); },
               {"normal/000004.png", "frame 4", "zero-length normals"});
  // Wrong size.
  write_image(frame_file(dir, r, FileKind::Color, 4), torch::rand({3, 5, 8}));
  expect_error([&] { read_color_file(frame_file(dir, r, FileKind::Color, 4), 4, r); },
               {"color/000004.png", "frame 4", "does not match the resolution 8x6"});
  // Corrupt and missing.
  std::ofstream(frame_file(dir, r, FileKind::Edge, 4), std::ios::trunc) << "garbage";
  expect_error([&] { read_edge_file(frame_file(dir, r, FileKind::Edge, 4), 4, r); }, {"edge/000004.png", "frame 4"});
  fs::remove(frame_file(dir, r, FileKind::Motion, 4));
  expect_error([&] { read_motion_file(frame_file(dir, r, FileKind::Motion, 4), 4, r); },
               {"motion/000004.exr", "frame 4", "missing"});
  // Edge values other than 0 and 1.
  write_image(frame_file(dir, r, FileKind::Edge, 4), torch::full({1, 6, 8}, 0.5f));
  expect_error([&] { read_edge_file(frame_file(dir, r, FileKind::Edge, 4), 4, r); }, {"edge value"});
}

}  // namespace
}  // namespace cgsr
