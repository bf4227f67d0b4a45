// Warping with motion vectors: synthetic ones, and the renderer's against its own frames.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "core/config.h"
#include "core/error.h"
#include "eval/temporal.h"
#include "render_data/renderer.h"
#include "render_data/scene_source.h"

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

namespace {
// PSNR over the pixels of `mask` ([1,1,H,W]) of two [1,3,H,W] images in [0,1].
double warp_check_psnr(const torch::Tensor& a, const torch::Tensor& b, const torch::Tensor& mask) {
  const auto m = mask.to(torch::kFloat32).expand_as(a);
  const double mse = (((a - b) * m).pow(2).sum() / m.sum()).item<double>();
  return 10.0 * std::log10(1.0 / mse);
}
}  // namespace

// The renderer's motion vectors against the renderer's own frames: warping frame f - 1 by frame
// f's motion reproduces frame f away from disocclusions (where the warped previous depth does not
// match) and far better than no warping at all.
TEST(Temporal, WarpingARenderedFrameByItsMotionReproducesThePreviousFrame) {
  const auto doc = config::Document::load_file(std::string(CGSR_SOURCE_DIR) + "/configs/scenes/default.yaml");
  const config::Block block{doc.root()["scene"], std::make_shared<config::Document>(doc), "scene"};
  const SceneBundle b = make_scene(block, 1);
  RenderSettings settings;
  settings.shadows = false;
  const SceneRenderer r(b.scene, settings);
  const int W = 128, H = 96, frames = 96;
  for (int f : {10, 40, 70}) {
    SCOPED_TRACE("frame " + std::to_string(f));
    const auto at = [&](int i) { return b.camera.at_frame(i, frames); };
    const GBuffer before = r.render(at(f - 1), at(f - 2), W, H, b.camera.near_plane, b.camera.far_plane);
    const GBuffer now = r.render(at(f), at(f - 1), W, H, b.camera.near_plane, b.camera.far_plane);
    const auto motion = now.motion.unsqueeze(0);
    const Warped color = warp_previous(before.color.unsqueeze(0), motion);
    const Warped depth = warp_previous(before.depth.nan_to_num(0, 1e6, 0).unsqueeze(0), motion);
    const auto current_depth = now.depth.nan_to_num(0, 1e6, 0).unsqueeze(0);
    // Same surface: the warped depth within 15% (a frame moves the camera by a fraction of the depth).
    const auto same = color.valid & ((depth.image - current_depth).abs() < 0.15 * current_depth);
    const double kept = same.to(torch::kFloat32).mean().item<double>();
    EXPECT_GT(kept, 0.5);
    const double warped = warp_check_psnr(color.image, now.color.unsqueeze(0), same);
    const double unwarped = warp_check_psnr(before.color.unsqueeze(0), now.color.unsqueeze(0), same);
    std::printf("frame %d: %.1f%% kept, PSNR warped %.2f dB, unwarped %.2f dB\n", f, 100 * kept, warped, unwarped);
    EXPECT_GT(warped, 25.0);  // bilinear resampling of fine textures limits it
    EXPECT_GT(warped, unwarped + 5.0);
  }
}
