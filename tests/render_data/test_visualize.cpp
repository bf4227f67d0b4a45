// Preview montages: LR (enlarged) beside HR per channel, also for captures that hold a channel at
// one resolution only.
#include <gtest/gtest.h>

#include <torch/torch.h>

#include "core/error.h"
#include "render_data/visualize.h"

namespace cgsr {
namespace {

Frame colour_frame(int w, int h) {
  Frame f;
  f.width = w;
  f.height = h;
  f.color = torch::full({3, h, w}, 200, torch::kUInt8);
  return f;
}

TEST(Visualize, AChannelOneResolutionLacksLeavesItsCellBlack) {
  Frame lr = colour_frame(4, 3);
  const Frame hr = colour_frame(8, 6);
  lr.depth = torch::full({1, 3, 4}, 2.0f);
  const auto m = montage(lr, hr, {PreviewChannel::Color, PreviewChannel::Depth});
  ASSERT_EQ(m.sizes(), (std::vector<int64_t>{3, 2 * 6 + 4, 2 * 8 + 4}));
  const auto depth_row = m.slice(1, 6 + 4, 2 * 6 + 4);
  EXPECT_GT(depth_row.slice(2, 0, 8).max().item<float>(), 0.0f);   // LR depth drawn
  EXPECT_EQ(depth_row.slice(2, 8 + 4).max().item<float>(), 0.0f);  // HR has none: black
  EXPECT_THROW(montage(lr, hr, {PreviewChannel::Normal}), Error);  // neither has it
}

TEST(Visualize, TilesFramesRowByRowWithWhiteGaps) {
  std::vector<Frame> frames{colour_frame(4, 3), colour_frame(4, 3), colour_frame(4, 3)};
  frames[2].color.fill_(0);
  const auto grid = tile_frames(frames, PreviewChannel::Color, 2);
  ASSERT_EQ(grid.sizes(), (std::vector<int64_t>{3, 2 * 3 + 4, 2 * 4 + 4}));
  EXPECT_NEAR(grid[0][0][0].item<float>(), 200 / 255.0f, 1e-6);   // frame 0, top left
  EXPECT_EQ(grid[0][3][0].item<float>(), 1.0f);                   // the gap between rows
  EXPECT_EQ(grid.slice(1, 7).slice(2, 0, 4).max().item<float>(), 0.0f);  // frame 2 starts row 2
  EXPECT_EQ(grid.slice(1, 7).slice(2, 8).min().item<float>(), 1.0f);     // no fourth frame: white
  frames.push_back(colour_frame(8, 6));
  EXPECT_THROW(tile_frames(frames, PreviewChannel::Color, 2), Error);    // sizes differ
  EXPECT_THROW(tile_frames(frames, PreviewChannel::Depth, 2), Error);    // no depth
}

}  // namespace
}  // namespace cgsr
