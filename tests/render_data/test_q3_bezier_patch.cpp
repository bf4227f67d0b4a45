// Bezier patch tessellation: exact points on the biquadratic surface, shared borders between
// sub-patches, bit-identical borders between separate grids (no cracks), and the BSP's winding.
#include <gtest/gtest.h>

#include <random>

#include "render_data/q3/bezier_patch.h"
#include "tests/render_data/q3_test_map.h"

namespace cgsr::q3 {
namespace {

std::vector<BspVertex> random_grid(int width, int height, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u(-100, 100);
  std::vector<BspVertex> grid(width * height);
  for (int r = 0; r < height; ++r)
    for (int c = 0; c < width; ++c) {
      BspVertex& v = grid[r * width + c];
      v.position = {c * 64.0f + u(rng) * 0.2f, r * 64.0f + u(rng) * 0.2f, u(rng)};
      v.normal = {0, 0, 1};
      v.uv = {static_cast<float>(c), static_cast<float>(r)};
      v.lightmap_uv = {c * 0.1f, r * 0.1f};
    }
  return grid;
}

// Reference: sum_i sum_j B_i(u) B_j(v) P[j][i] in double precision.
Vec3 reference(const std::vector<BspVertex>& g, double u, double v) {
  const double bu[3] = {(1 - u) * (1 - u), 2 * u * (1 - u), u * u}, bv[3] = {(1 - v) * (1 - v), 2 * v * (1 - v), v * v};
  double p[3] = {0, 0, 0};
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) p[k] += bu[i] * bv[j] * g[j * 3 + i].position[k];
  return {static_cast<float>(p[0]), static_cast<float>(p[1]), static_cast<float>(p[2])};
}

TEST(Q3BezierPatch, EvaluatesTheBiquadraticSurfaceExactly) {
  const auto grid = random_grid(3, 3, 1);
  for (const auto& [u, v] : {std::pair{0.0, 0.0}, {0.25, 0.5}, {0.5, 0.5}, {1.0, 0.75}, {0.125, 1.0}}) {
    const PatchVertex p = evaluate_patch(grid.data(), static_cast<float>(u), static_cast<float>(v));
    const Vec3 r = reference(grid, u, v);
    EXPECT_NEAR(p.position.x, r.x, 1e-3) << u << "," << v;
    EXPECT_NEAR(p.position.y, r.y, 1e-3);
    EXPECT_NEAR(p.position.z, r.z, 1e-3);
    EXPECT_NEAR(p.uv.x, 2 * u, 1e-5);  // uv control values are linear in the index
    EXPECT_NEAR(p.lightmap_uv.y, 0.2 * v, 1e-5);
  }
  // The corners are the corner control points, bit for bit.
  EXPECT_TRUE(testing::same(evaluate_patch(grid.data(), 0, 0).position, grid[0].position));
  EXPECT_TRUE(testing::same(evaluate_patch(grid.data(), 1, 1).position, grid[8].position));
}

TEST(Q3BezierPatch, TessellationSamplesTheSurfaceAtEvenSteps) {
  const auto grid = random_grid(3, 3, 2);
  const int level = 4;
  const TessellatedPatch t = tessellate_patch(grid, 3, 3, level);
  ASSERT_EQ(t.columns, 5);
  ASSERT_EQ(t.rows, 5);
  EXPECT_EQ(t.vertices.size(), 25u);
  EXPECT_EQ(t.indices.size(), 4u * 4 * 6);
  for (int row = 0; row <= level; ++row)
    for (int col = 0; col <= level; ++col) {
      const Vec3 r = reference(grid, col / 4.0, row / 4.0);
      const Vec3 p = t.vertices[row * t.columns + col].position;
      EXPECT_NEAR(p.x, r.x, 1e-3);
      EXPECT_NEAR(p.y, r.y, 1e-3);
      EXPECT_NEAR(p.z, r.z, 1e-3);
    }
}

TEST(Q3BezierPatch, SubPatchesShareTheirBorder) {
  // 5x3 control points: two 3x3 patches side by side sharing control column 2.
  const auto grid = random_grid(5, 3, 3);
  const int level = 3;
  const TessellatedPatch t = tessellate_patch(grid, 5, 3, level);
  EXPECT_EQ(t.columns, 2 * level + 1);
  EXPECT_EQ(t.rows, level + 1);
  EXPECT_EQ(t.indices.size(), static_cast<size_t>(2 * level * level * 6));
  // The shared column passes through the shared control points (rows 0 and 2 are on the surface).
  EXPECT_TRUE(testing::same(t.vertices[level].position, grid[2].position));
  EXPECT_TRUE(testing::same(t.vertices[level * t.columns + level].position, grid[2 * 5 + 2].position));
  // Every index is in range and every vertex is used: no duplicate border vertices.
  std::vector<int> used(t.vertices.size(), 0);
  for (uint32_t i : t.indices) {
    ASSERT_LT(i, t.vertices.size());
    used[i] = 1;
  }
  for (int u : used) EXPECT_EQ(u, 1);
}

TEST(Q3BezierPatch, SeparateGridsSharingAnEdgeMatchBitForBit) {
  // Grid A's right column is grid B's left column in the opposite direction.
  const auto a = random_grid(3, 3, 4);
  auto b = random_grid(3, 3, 5);
  for (int r = 0; r < 3; ++r) b[r * 3 + 0].position = a[(2 - r) * 3 + 2].position;
  for (int level : {1, 3, 4, 7, 8}) {
    const TessellatedPatch ta = tessellate_patch(a, 3, 3, level), tb = tessellate_patch(b, 3, 3, level);
    for (int k = 0; k <= level; ++k) {
      const Vec3 pa = ta.vertices[k * ta.columns + level].position;
      const Vec3 pb = tb.vertices[(level - k) * tb.columns + 0].position;
      EXPECT_EQ(pa.x, pb.x) << "level " << level << " step " << k;
      EXPECT_EQ(pa.y, pb.y);
      EXPECT_EQ(pa.z, pb.z);
    }
  }
}

TEST(Q3BezierPatch, TrianglesAreClockwiseSeenFromTheFrontLikeTheBsp) {
  for (float normal_sign : {1.0f, -1.0f}) {
    auto grid = random_grid(3, 5, 6);
    for (auto& v : grid) v.normal = {0, 0, normal_sign};
    for (auto& v : grid) v.position.z *= 0.1f;  // mostly flat, facing +-z
    const TessellatedPatch t = tessellate_patch(grid, 3, 5, 4);
    for (size_t k = 0; k < t.indices.size(); k += 3) {
      const Vec3 a = t.vertices[t.indices[k]].position, b = t.vertices[t.indices[k + 1]].position,
                 c = t.vertices[t.indices[k + 2]].position;
      EXPECT_LT(dot(cross(b - a, c - a), t.vertices[t.indices[k]].normal), 0);
    }
  }
}

}  // namespace
}  // namespace cgsr::q3
