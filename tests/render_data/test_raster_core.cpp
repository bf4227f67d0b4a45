// Coverage of the triangle pipeline: pixel-centre sampling, the top-left rule, near clipping.
#include <gtest/gtest.h>

#include <cmath>

#include "render_data/raster_core.h"

namespace cgsr {
namespace {

// Clip coordinates (w = 1) of a pixel position in a W x H image: exact for these small sizes.
Vec4 at_pixel(double px, double py, int W, int H, float w = 1.0f) {
  return {static_cast<float>((px / W * 2 - 1) * w), static_cast<float>((1 - py / H * 2) * w), 0.0f, w};
}

struct Fixture {
  std::vector<Vec4> clip;
  std::vector<float> depth;
  std::vector<uint32_t> indices;
  std::vector<uint8_t> cull, alpha;
  RasterInput input(int W, int H) {
    cull.assign(indices.size() / 3, 0);
    alpha.assign(indices.size() / 3, 0);
    RasterInput in;
    in.clip = &clip;
    in.depth = &depth;
    in.indices = &indices;
    in.cull_back = &cull;
    in.alpha_tested = &alpha;
    in.width = W;
    in.height = H;
    in.tile_size = 4;  // several tiles even in a tiny image
    return in;
  }
};

// Reference: is the centre inside the triangle (strictly, no centre lies on an edge here)?
bool inside_reference(const double x[3], const double y[3], double px, double py) {
  double s[3];
  for (int k = 0; k < 3; ++k) {
    const int a = k, b = (k + 1) % 3;
    s[k] = (x[b] - x[a]) * (py - y[a]) - (y[b] - y[a]) * (px - x[a]);
  }
  return (s[0] > 0 && s[1] > 0 && s[2] > 0) || (s[0] < 0 && s[1] < 0 && s[2] < 0);
}

TEST(RasterCore, KnownTriangleCoversExactlyTheExpectedPixelCentres) {
  const int W = 12, H = 10;
  const double x[3] = {1.3, 10.7, 3.9}, y[3] = {0.8, 4.2, 9.6};
  Fixture f;
  for (int k = 0; k < 3; ++k) {
    f.clip.push_back(at_pixel(x[k], y[k], W, H));
    f.depth.push_back(1.0f);
  }
  f.indices = {0, 1, 2};
  const auto in = f.input(W, H);
  VisibilityBuffer vis;
  rasterize(in, setup_triangles(in), vis);
  int covered = 0;
  for (int i = 0; i < H; ++i)
    for (int j = 0; j < W; ++j) {
      const bool expected = inside_reference(x, y, j + 0.5, i + 0.5);
      EXPECT_EQ(vis.screen_index[i * W + j] >= 0, expected) << "pixel row " << i << " col " << j;
      covered += expected;
    }
  EXPECT_GT(covered, 20);  // the fixture is not degenerate
}

TEST(RasterCore, HandPickedTriangleCoverage) {
  // Pixel-space triangle (0.5,0.5) (4.5,0.5) (0.5,4.5) in an 8x8 image (exact in clip space): its left and top edges pass
  // through pixel centres (included, top-left rule) and its hypotenuse x + y = 5 passes through
  // centres too (excluded: a right/bottom edge).
  const int W = 8, H = 8;
  Fixture f;
  f.clip = {at_pixel(0.5, 0.5, W, H), at_pixel(4.5, 0.5, W, H), at_pixel(0.5, 4.5, W, H)};
  f.depth = {1, 1, 1};
  f.indices = {0, 2, 1};  // either winding must give the same coverage
  const auto in = f.input(W, H);
  VisibilityBuffer vis;
  rasterize(in, setup_triangles(in), vis);
  for (int i = 0; i < H; ++i)
    for (int j = 0; j < W; ++j) {
      const bool expected = i + j < 4;  // centres with (j+0.5) + (i+0.5) < 5
      EXPECT_EQ(vis.screen_index[i * W + j] >= 0, expected) << "pixel row " << i << " col " << j;
    }
}

TEST(RasterCore, SharedEdgesCoverEveryCentreExactlyOnce) {
  // A square split along its diagonal, which passes exactly through pixel centres; plus a fan of
  // triangles around an interior vertex that sits on a pixel centre.
  const int W = 8, H = 8;
  Fixture f;
  f.clip = {at_pixel(0, 0, W, H), at_pixel(8, 0, W, H), at_pixel(8, 8, W, H), at_pixel(0, 8, W, H),
            at_pixel(4.5, 3.5, W, H)};
  f.depth = {1, 1, 1, 1, 1};
  f.indices = {0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4};
  auto in = f.input(W, H);
  const auto tris = setup_triangles(in);
  std::vector<int> count(W * H, 0);
  for (size_t t = 0; t < tris.size(); ++t) {
    // Rasterize each triangle alone and count how often each centre is covered.
    std::vector<ScreenTriangle> one{tris[t]};
    VisibilityBuffer vis;
    rasterize(in, one, vis);
    for (int p = 0; p < W * H; ++p) count[p] += vis.screen_index[p] >= 0;
  }
  for (int p = 0; p < W * H; ++p) EXPECT_EQ(count[p], 1) << "pixel " << p;
}

TEST(RasterCore, DiagonalThroughCentresIsCoveredOnce) {
  const int W = 8, H = 8;
  Fixture f;
  f.clip = {at_pixel(0, 0, W, H), at_pixel(8, 0, W, H), at_pixel(8, 8, W, H), at_pixel(0, 8, W, H)};
  f.depth = {1, 1, 1, 1};
  f.indices = {0, 1, 2, 0, 2, 3};  // the shared diagonal x = y passes through every (k+0.5, k+0.5)
  const auto in = f.input(W, H);
  const auto tris = setup_triangles(in);
  ASSERT_EQ(tris.size(), 2u);
  std::vector<int> count(W * H, 0);
  for (const auto& t : tris) {
    VisibilityBuffer vis;
    rasterize(in, {t}, vis);
    for (int p = 0; p < W * H; ++p) count[p] += vis.screen_index[p] >= 0;
  }
  for (int p = 0; p < W * H; ++p) EXPECT_EQ(count[p], 1) << "pixel " << p;
}

TEST(RasterCore, DepthTestKeepsTheNearestSurface) {
  const int W = 8, H = 8;
  Fixture f;
  f.clip = {at_pixel(0, 0, W, H), at_pixel(16, 0, W, H), at_pixel(0, 16, W, H)};
  f.depth = {5, 5, 5};
  f.clip.insert(f.clip.end(), {at_pixel(0, 0, W, H), at_pixel(8, 0, W, H), at_pixel(0, 8, W, H)});
  f.depth.insert(f.depth.end(), {2, 2, 2});
  f.indices = {0, 1, 2, 3, 4, 5};
  const auto in = f.input(W, H);
  const auto tris = setup_triangles(in);
  VisibilityBuffer vis;
  rasterize(in, tris, vis);
  EXPECT_EQ(tris[vis.screen_index[0]].triangle, 1u);
  EXPECT_FLOAT_EQ(vis.depth[0], 2.0f);
  EXPECT_EQ(tris[vis.screen_index[7 * W + 7]].triangle, 0u);
  EXPECT_FLOAT_EQ(vis.depth[7 * W + 7], 5.0f);
}

TEST(RasterCore, NearPlaneClippingKeepsTheVisiblePart) {
  // A triangle crossing the near plane (one vertex behind the camera): the part in front is
  // still drawn and its depth attribute stays perspective-correct.
  const int W = 16, H = 16;
  Fixture f;
  // Perspective-like clip coordinates: w = view depth.
  f.clip = {Vec4{-2, -2, 0, 2}, Vec4{2, -2, 0, 2}, Vec4{0, 3, 0, -1}};
  f.depth = {2, 2, -1};
  f.indices = {0, 1, 2};
  auto in = f.input(W, H);
  in.w_min = 0.1f;
  const auto tris = setup_triangles(in);
  ASSERT_FALSE(tris.empty());
  VisibilityBuffer vis;
  rasterize(in, tris, vis);
  int covered = 0;
  for (int p = 0; p < W * H; ++p)
    if (vis.screen_index[p] >= 0) {
      ++covered;
      EXPECT_GE(vis.depth[p], 0.1f - 1e-4f);
      EXPECT_LE(vis.depth[p], 2.0f + 1e-4f);
    }
  EXPECT_GT(covered, 0);
  // The bottom row is the base of the triangle at depth 2.
  EXPECT_NEAR(vis.depth[(H - 1) * W + W / 2], 2.0f, 0.2f);
}

TEST(RasterCore, BackFacesAreCulledOnlyWhenAsked) {
  const int W = 4, H = 4;
  Fixture f;
  // Counter-clockwise in view space (y up) = front face.
  f.clip = {Vec4{-1, -1, 0, 1}, Vec4{1, -1, 0, 1}, Vec4{-1, 1, 0, 1}};
  f.depth = {1, 1, 1};
  f.indices = {0, 2, 1};  // clockwise: a back face
  auto in = f.input(W, H);
  auto tris = setup_triangles(in);
  ASSERT_EQ(tris.size(), 1u);
  EXPECT_FALSE(tris[0].front_facing);
  f.cull.assign(1, 1);
  in.cull_back = &f.cull;
  EXPECT_TRUE(setup_triangles(in).empty());
  f.indices = {0, 1, 2};
  tris = setup_triangles(in);
  ASSERT_EQ(tris.size(), 1u);
  EXPECT_TRUE(tris[0].front_facing);
}

}  // namespace
}  // namespace cgsr
