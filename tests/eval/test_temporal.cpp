// Warping with rendered motion vectors.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include "core/error.h"
#include "eval/temporal.h"

using namespace cgsr;

TEST(Temporal, IntegerMotionWarpsExactly) {
  // The scene moves one pixel left: a pixel at x was at x + 1 in the previous frame.
  torch::manual_seed(2);
  const auto previous = torch::rand({1, 3, 6, 8}, torch::kFloat64);
  const auto current = torch::cat({previous.slice(3, 1), previous.slice(3, 7)}, 3);
  auto motion = torch::zeros({1, 2, 6, 8}, torch::kFloat64);
  motion.select(1, 0).fill_(1.0);
  const auto warped = warp_previous(previous, motion);
  EXPECT_LT((warped.image.slice(3, 0, 7) - current.slice(3, 0, 7)).abs().max().item<double>(), 1e-12);
  EXPECT_FALSE(warped.valid[0][0][0][7].item<bool>());  // its source lies outside the frame
  EXPECT_TRUE(warped.valid[0][0][0][6].item<bool>());
  EXPECT_LT(warping_error(current, previous, motion), 1e-12);
}

TEST(Temporal, HalfPixelMotionInterpolates) {
  const auto previous = torch::arange(8, torch::kFloat64).view({1, 1, 1, 8}).expand({1, 1, 4, 8}).contiguous();
  auto motion = torch::zeros({1, 2, 4, 8}, torch::kFloat64);
  motion.select(1, 0).fill_(0.5);
  const auto warped = warp_previous(previous, motion);
  EXPECT_NEAR(warped.image[0][0][1][3].item<double>(), 3.5, 1e-12);
}

TEST(Temporal, StaticSceneHasNoErrorAndFlickerHasSome) {
  const auto frame = torch::rand({1, 3, 5, 5});
  const auto still = torch::zeros({1, 2, 5, 5});
  EXPECT_NEAR(warping_error(frame, frame, still), 0.0, 1e-5);
  EXPECT_NEAR(warping_error(frame + 0.1, frame, still), 0.1, 1e-5);
}

TEST(Temporal, ShapeMismatchIsAnError) {
  EXPECT_THROW(warp_previous(torch::rand({1, 3, 4, 4}), torch::zeros({1, 2, 4, 5})), Error);
}
