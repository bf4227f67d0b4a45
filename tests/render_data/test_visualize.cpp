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

}  // namespace
}  // namespace cgsr
