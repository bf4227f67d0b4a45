// Flips and rotations move pixels and transform normal and motion vectors consistently; colour
// augmentation reorders and scales colour channels only.
#include <gtest/gtest.h>

#include <torch/torch.h>

#include "core/error.h"
#include "render_data/augment.h"
#include "render_data/derive_channels.h"
#include "render_data/vec_math.h"

namespace cgsr {
namespace {

// Position (row, col) of the single marked pixel of a [1,H,W] image.
std::pair<int, int> marked(const torch::Tensor& img) {
  const auto idx = img[0].argmax().item<int64_t>();
  return {static_cast<int>(idx / img.size(2)), static_cast<int>(idx % img.size(2))};
}

TEST(Augment, MotionStillPointsToWhereThePixelWas) {
  // Pixel P at (row 3, col 5) moved there from Q at (row 9, col 2): motion at P = Q - P in
  // (x right, y down) = (-3, +6). After any flip/rotation, P' + motion' must land on Q'.
  const int H = 12, W = 10;
  auto p_mark = torch::zeros({1, H, W}), q_mark = torch::zeros({1, H, W});
  p_mark[0][3][5] = 1;
  q_mark[0][9][2] = 1;
  auto motion = torch::zeros({2, H, W});
  motion[0][3][5] = -3;
  motion[1][3][5] = 6;
  for (int i = 0; i < 8; ++i) {
    SCOPED_TRACE(i);
    const Augmentation a = Augmentation::from_index(i);
    const auto p2 = marked(augment_image(p_mark, a)), q2 = marked(augment_image(q_mark, a));
    const auto m2 = augment_info(motion, {RenderChannel::Motion}, a);
    const float dx = m2[0][p2.first][p2.second].item<float>(), dy = m2[1][p2.first][p2.second].item<float>();
    EXPECT_EQ(p2.second + static_cast<int>(dx), q2.second);
    EXPECT_EQ(p2.first + static_cast<int>(dy), q2.first);
  }
}

TEST(Augment, NormalsAgreeWithTheAugmentedGeometry) {
  // Normals derived from a tilted plane's depth, then augmented, must equal the normals
  // derived from the augmented depth (a square image so the field of view is unchanged).
  const int N = 24;
  const double vfov = 60, f = N / 2.0 / std::tan(vfov * M_PI / 360.0);
  auto depth = torch::empty({1, N, N});
  const Vec3 n = normalize(Vec3{0.4f, -0.3f, 1.0f});
  for (int i = 0; i < N; ++i)
    for (int j = 0; j < N; ++j) {
      const double u = (j + 0.5 - N / 2.0) / f, v = (N / 2.0 - (i + 0.5)) / f;
      depth[0][i][j] = static_cast<float>(-5.0 * n.z / (n.x * u + n.y * v - n.z));
    }
  const auto normals = normals_from_depth(depth, vfov);
  for (int i = 0; i < 8; ++i) {
    SCOPED_TRACE(i);
    const Augmentation a = Augmentation::from_index(i);
    const auto moved = augment_info(torch::cat({depth, normals}), {RenderChannel::Depth, RenderChannel::Normal}, a);
    const auto expected = normals_from_depth(moved.slice(0, 0, 1), vfov);
    EXPECT_LT((moved.slice(0, 1, 4) - expected).abs().max().item<float>(), 2e-3f);
  }
}

TEST(Augment, HorizontalFlipNegatesXComponentsOnly) {
  auto info = torch::rand({6, 4, 4});  // depth, normal xyz, motion xy
  const std::vector<RenderChannel> ch = {RenderChannel::Depth, RenderChannel::Normal, RenderChannel::Motion};
  const auto out = augment_info(info, ch, Augmentation{true, 0});
  const auto moved = info.flip({2});
  EXPECT_TRUE(torch::allclose(out[0], moved[0]));
  EXPECT_TRUE(torch::allclose(out[1], -moved[1]));
  EXPECT_TRUE(torch::allclose(out[2], moved[2]));
  EXPECT_TRUE(torch::allclose(out[3], moved[3]));
  EXPECT_TRUE(torch::allclose(out[4], -moved[4]));
  EXPECT_TRUE(torch::allclose(out[5], moved[5]));
  // Batched input works the same.
  EXPECT_TRUE(torch::allclose(augment_info(info.unsqueeze(0), ch, Augmentation{true, 1})[0],
                              augment_info(info, ch, Augmentation{true, 1})));
}

TEST(Augment, ColourDrawsCoverEveryOrderAndTheGainRangeSymmetrically) {
  const float m = ColorAugmentation::kMaxGain;
  EXPECT_EQ(ColorAugmentation::from_uniform(0, 0).permutation, 0);
  EXPECT_EQ(ColorAugmentation::from_uniform(0.999, 0).permutation, 5);
  EXPECT_FLOAT_EQ(ColorAugmentation::from_uniform(0, 0).gain, 1 / m);
  EXPECT_FLOAT_EQ(ColorAugmentation::from_uniform(0, 0.5).gain, 1.0f);  // log-uniform: 1 in the middle
  EXPECT_NEAR(ColorAugmentation::from_uniform(0, 0.999999).gain, m, 1e-5);
  EXPECT_THROW(ColorAugmentation::from_uniform(1.0, 0), Error);
}

TEST(Augment, ColourReordersAndScalesChannelsWithinZeroToOne) {
  auto color = torch::rand({2, 3, 5, 4});
  // Order 3 is (G, B, R); a gain of 1.5 saturates what was above 2/3.
  const auto out = augment_color(color, ColorAugmentation{3, 1.5f});
  const auto expected = torch::stack({color.select(1, 1), color.select(1, 2), color.select(1, 0)}, 1).mul(1.5f).clamp(0, 1);
  EXPECT_TRUE(torch::allclose(out, expected));
  EXPECT_LE(out.max().item<float>(), 1.0f);
  EXPECT_TRUE(torch::equal(augment_color(color[0], ColorAugmentation{}), color[0]));  // the identity
  EXPECT_THROW(augment_color(torch::rand({4, 5, 4}), ColorAugmentation{1, 1.0f}), Error);  // not RGB
}

}  // namespace
}  // namespace cgsr
