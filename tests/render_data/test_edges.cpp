// Edge detection on synthetic G-buffers: depth steps, smooth planes, id changes, creases, and
// frames where (almost) every pixel is an edge; the one-pixel dilation of edge maps.
#include <gtest/gtest.h>

#include <torch/torch.h>

#include "render_data/edges.h"

namespace cgsr {
namespace {

// Depth of a tilted plane: 1/z affine in the pixel coordinates (what a perspective camera sees).
torch::Tensor plane_depth(int H, int W, double a, double b, double c) {
  auto j = torch::arange(W, torch::kFloat64).view({1, W}).expand({H, W});
  auto i = torch::arange(H, torch::kFloat64).view({H, 1}).expand({H, W});
  return torch::reciprocal(a * j + b * i + c).to(torch::kFloat32).unsqueeze(0);
}

TEST(Edges, SmoothPlanesHaveNone) {
  // A floor receding steeply: big relative depth changes between rows, but no discontinuity.
  const auto d = plane_depth(40, 50, 0.0, 0.02, 0.01);
  EXPECT_EQ(detect_edges(d, {}, {}, EdgeSettings{}).sum().item<float>(), 0.0f);
}

TEST(Edges, DepthStepMarksTheNearSide) {
  auto d = torch::full({1, 20, 30}, 10.0f);
  d.slice(2, 15, 30).fill_(4.0f);  // right half nearer
  const auto e = detect_edges(d, {}, {}, EdgeSettings{});
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 30; ++j) EXPECT_EQ(e[0][i][j].item<float>(), j == 15 ? 1.0f : 0.0f) << i << "," << j;
}

TEST(Edges, SkyBorderIdChangeAndCrease) {
  auto d = torch::full({1, 10, 10}, 3.0f);
  d.slice(1, 0, 3).fill_(std::numeric_limits<float>::infinity());  // sky in the top rows
  auto ids = torch::zeros({1, 10, 10}, torch::kInt32);
  ids.slice(1, 6, 10).slice(2, 0, 2).fill_(5);  // a decal-like object in the same plane
  auto n = torch::zeros({3, 10, 10});
  n[2].fill_(1.0f);
  n.slice(1, 0, 10).slice(2, 7, 10).zero_();
  n[0].slice(0, 0, 10).slice(1, 7, 10).fill_(1.0f);  // a 90-degree crease at column 7
  const auto e = detect_edges(d, n, ids, EdgeSettings{});
  EXPECT_EQ(e[0][3][4].item<float>(), 1.0f);  // geometry next to sky
  EXPECT_EQ(e[0][0][4].item<float>(), 0.0f);  // sky itself never
  EXPECT_EQ(e[0][7][1].item<float>(), 1.0f);  // id change (tie in depth: the left pixel)
  EXPECT_EQ(e[0][5][6].item<float>(), 1.0f);  // crease (tie: the left pixel)
  EXPECT_EQ(e[0][5][3].item<float>(), 0.0f);  // plain interior
  EdgeSettings no_ids;
  no_ids.id_changes = false;
  EXPECT_EQ(detect_edges(d, n, ids, no_ids)[0][7][1].item<float>(), 0.0f);
}

TEST(Edges, AlternatingDepthMakesEveryNearPixelAnEdge) {
  // A checkerboard of near and far pixels: the extreme "everything is an edge" frame.
  auto d = torch::full({1, 16, 16}, 20.0f);
  for (int i = 0; i < 16; ++i)
    for (int j = (i % 2); j < 16; j += 2) d[0][i][j] = 2.0f;
  const auto e = detect_edges(d, {}, {}, EdgeSettings{});
  const auto near = d == 2.0f;
  EXPECT_TRUE((e.gt(0.5f) == near).all().item<bool>());
  EXPECT_EQ(e.sum().item<float>(), 128.0f);
}

TEST(Edges, ExtremeDepthRangeStaysFinite) {
  auto d = torch::full({1, 8, 8}, 1e6f);
  d.slice(2, 4, 8).fill_(1e-3f);
  const auto e = detect_edges(d, {}, {}, EdgeSettings{});
  EXPECT_TRUE(torch::isfinite(e).all().item<bool>());
  EXPECT_EQ(e[0][3][4].item<float>(), 1.0f);
  EXPECT_EQ(e.sum().item<float>(), 8.0f);
}

TEST(DilateEdges, GrowsAPixelToItsThreeByThreeBlock) {
  auto e = torch::zeros({1, 6, 7}, torch::kUInt8);
  e[0][2][3] = 1;
  const auto d = dilate_edges(e);
  ASSERT_EQ(d.sizes(), e.sizes());
  EXPECT_EQ(d.scalar_type(), torch::kBool);
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 7; ++j)
      EXPECT_EQ(d[0][i][j].item<bool>(), i >= 1 && i <= 3 && j >= 2 && j <= 4) << i << "," << j;
}

TEST(DilateEdges, ClampsTheWindowAtTheBorders) {
  auto e = torch::zeros({5, 4}, torch::kFloat32);  // any type: nonzero is an edge
  e[0][0] = 1.0f;
  e[4][3] = 0.5f;
  const auto d = dilate_edges(e);
  ASSERT_EQ(d.sizes(), e.sizes());
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 4; ++j)
      EXPECT_EQ(d[i][j].item<bool>(), (i <= 1 && j <= 1) || (i >= 3 && j >= 2)) << i << "," << j;
}

}  // namespace
}  // namespace cgsr
