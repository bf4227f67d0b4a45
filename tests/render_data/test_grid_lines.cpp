// Detection and removal of the periodic tile-grid lines in CGSR edge masks.
#include <gtest/gtest.h>

#include <torch/torch.h>

#include "render_data/grid_lines.h"

namespace cgsr {
namespace {

torch::Tensor object_edges(int H, int W) {
  // A rectangle outline and a diagonal: real edges.
  auto e = torch::zeros({1, H, W}, torch::kUInt8);
  e[0].slice(0, 10, 11).slice(1, 5, 40).fill_(1);
  e[0].slice(0, 30, 31).slice(1, 5, 40).fill_(1);
  e[0].slice(1, 5, 6).slice(0, 10, 31).fill_(1);
  e[0].slice(1, 39, 40).slice(0, 10, 31).fill_(1);
  for (int k = 0; k < 40; ++k) e[0][k + 5][k + 10] = 1;
  return e;
}

TEST(GridLines, FindsAndRemovesPeriodicLines) {
  const int H = 60, W = 80;
  const auto truth = object_edges(H, W);
  auto noisy = truth.clone();
  for (int i = 3; i < H; i += 16) noisy[0][i].fill_(1);     // rows 3, 19, 35, 51
  for (int j = 11; j < W; j += 16) noisy[0].select(1, j).fill_(1);  // cols 11, 27, 43, 59, 75
  const GridLines g = detect_grid_lines(noisy);
  EXPECT_EQ(g.row_period, 16);
  EXPECT_EQ(g.row_offset, 3);
  EXPECT_EQ(g.col_period, 16);
  EXPECT_EQ(g.col_offset, 11);
  const auto cleaned = remove_grid_lines(noisy, g);
  // Every grid pixel that is not a real edge is gone; real edges off the lines stay.
  auto grid = torch::zeros({1, H, W}, torch::kBool);
  grid[0].slice(0, 3, H, 16).fill_(true);
  grid[0].slice(1, 11, W, 16).fill_(true);
  EXPECT_TRUE((cleaned.masked_select(~grid) == truth.masked_select(~grid)).all().item<bool>());
  const auto spurious = cleaned.gt(0) & truth.eq(0);
  EXPECT_EQ(spurious.sum().item<int64_t>(), 0);
  // Real edges crossing a grid line survive there: column 5 and the diagonal cross row 19, the
  // rectangle's top edge crosses columns 11 and 27.
  EXPECT_EQ(cleaned[0][19][5].item<uint8_t>(), 1);
  EXPECT_EQ(cleaned[0][19][24].item<uint8_t>(), 1);
  EXPECT_EQ(cleaned[0][10][27].item<uint8_t>(), 1);
  // Grid pixels next to (but not on) a crossing edge are removed.
  EXPECT_EQ(cleaned[0][19][4].item<uint8_t>(), 0);
  EXPECT_EQ(cleaned[0][19][6].item<uint8_t>(), 0);
}

TEST(GridLines, CleanMasksAndAllEdgeMasksAreLeftAlone) {
  const auto truth = object_edges(60, 80);
  EXPECT_FALSE(detect_grid_lines(truth).found());
  const auto all = torch::ones({1, 60, 80}, torch::kUInt8);
  const GridLines g = detect_grid_lines(all);
  EXPECT_FALSE(g.found());
  EXPECT_TRUE(torch::equal(remove_grid_lines(all, g), all));
}

}  // namespace
}  // namespace cgsr
