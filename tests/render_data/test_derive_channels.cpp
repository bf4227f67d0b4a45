// Channels reconstructed from depth: normals of known planes, normal angles, derived edges.
#include <gtest/gtest.h>

#include <torch/torch.h>

#include <cmath>

#include "core/error.h"
#include "render_data/derive_channels.h"
#include "render_data/vec_math.h"

namespace cgsr {
namespace {

// Linear depth of the plane n . p = d seen by a pinhole camera (vfov, principal point at the
// centre): along the ray r = (u, v, -1), t = d / (n . r).
torch::Tensor depth_of_plane(int H, int W, double vfov, Vec3 n, double dist) {
  const double f = H / 2.0 / std::tan(vfov * M_PI / 360.0);
  auto out = torch::empty({1, H, W});
  for (int i = 0; i < H; ++i)
    for (int j = 0; j < W; ++j) {
      const double u = (j + 0.5 - W / 2.0) / f, v = (H / 2.0 - (i + 0.5)) / f;
      const double nr = n.x * u + n.y * v - n.z;
      out[0][i][j] = nr < 0 ? static_cast<float>(dist / nr) : std::numeric_limits<float>::infinity();
    }
  return out;
}

TEST(DeriveChannels, NormalsOfKnownPlanes) {
  const double vfov = 60;
  for (const Vec3 n : {Vec3{0, 0, 1}, normalize(Vec3{0.5f, 0.3f, 1}), normalize(Vec3{0, 1, 0.4f})}) {
    // Plane through (0, 0, -6) with normal n (facing the camera): n . p = n . (0,0,-6).
    const auto depth = depth_of_plane(24, 32, vfov, n, -6.0 * n.z);
    const auto derived = normals_from_depth(depth, vfov);
    const auto finite = torch::isfinite(depth[0]);
    for (int c = 0; c < 3; ++c) {
      const auto err = (derived[c] - n[c]).abs().masked_select(finite);
      EXPECT_LT(err.max().item<float>(), 2e-3f) << "component " << c;
    }
  }
}

TEST(DeriveChannels, NormalsDoNotBleedAcrossDepthSteps) {
  auto depth = torch::full({1, 16, 16}, 8.0f);
  depth.slice(2, 8, 16).fill_(3.0f);
  const auto n = normals_from_depth(depth, 60);
  // Both sides are fronto-parallel-ish planes: z component near 1 right up to the step.
  EXPECT_GT(n[2].min().item<float>(), 0.95f);
}

TEST(DeriveChannels, SkyGetsZeroNormalAndAngle) {
  auto depth = torch::full({1, 6, 6}, 2.0f);
  depth.slice(1, 0, 2).fill_(std::numeric_limits<float>::infinity());
  const auto n = normals_from_depth(depth, 60);
  EXPECT_EQ(n.slice(1, 0, 2).abs().max().item<float>(), 0.0f);
  const auto a = normal_angle_from_normals(n, 60);
  EXPECT_EQ(a.slice(1, 0, 2).abs().max().item<float>(), 0.0f);
  EXPECT_LT(a.slice(1, 2, 6).max().item<float>(), 0.5f);
}

TEST(DeriveChannels, NormalAngleOfAGrazingPlaneIsLarge) {
  const Vec3 n = normalize(Vec3{0, 1, 0.05f});  // nearly a floor seen from eye level
  const auto depth = depth_of_plane(24, 32, 60, n, -1.5);
  const auto a = normal_angle_from_normals(normals_from_depth(depth, 60), 60);
  const auto finite = torch::isfinite(depth[0]);
  EXPECT_GT(a[0].masked_select(finite).mean().item<float>(), 0.7f);
}

TEST(DeriveChannels, FrameDerivationReportsWhatItCannotDo) {
  Frame f;
  f.width = 8;
  f.height = 8;
  f.color = torch::zeros({3, 8, 8}, torch::kUInt8);
  f.depth = torch::full({1, 8, 8}, 4.0f);
  f.depth.slice(2, 4, 8).fill_(1.0f);
  derive_channels(f, {RenderChannel::Edge, RenderChannel::Normal, RenderChannel::NormalAngle}, 60, {});
  ASSERT_TRUE(f.edge.defined() && f.normal.defined() && f.normal_angle.defined());
  EXPECT_EQ(f.edge.sum().item<int64_t>(), 8);
  EXPECT_THROW(derive_channels(f, {RenderChannel::Motion}, 60, {}), Error);
  Frame no_depth;
  no_depth.width = no_depth.height = 8;
  EXPECT_THROW(derive_channels(no_depth, {RenderChannel::Edge}, 60, {}), Error);
}

}  // namespace
}  // namespace cgsr
