// Classic upscalers: conventions, exactness on simple signals, and FSR's edge behaviour.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "train/baselines/fsr1.h"
#include "train/baselines/interpolation.h"

using namespace cgsr;

namespace {
using Upscale = std::function<torch::Tensor(const torch::Tensor&, int)>;
const std::vector<std::pair<std::string, Upscale>>& all_upscalers() {
  static const std::vector<std::pair<std::string, Upscale>> all = {
      {"nearest", upscale_nearest},
      {"bilinear", upscale_bilinear},
      {"bicubic", upscale_bicubic},
      {"lanczos", [](const torch::Tensor& x, int s) { return upscale_lanczos(x, s); }},
      {"fsr", [](const torch::Tensor& x, int s) { return upscale_fsr1(x, s); }},
  };
  return all;
}

// A vertical step edge rendered at a given resolution, with the edge at a fixed fraction.
torch::Tensor step_edge(int64_t h, int64_t w) {
  auto img = torch::zeros({1, 3, h, w});
  img.slice(3, w * 3 / 8, w).fill_(0.8);
  img.slice(3, 0, w * 3 / 8).fill_(0.1);
  return img;
}
}  // namespace

TEST(Baselines, ShapesAndConstantImagesForEveryScale) {
  for (const auto& [name, upscale] : all_upscalers())
    for (int scale : {2, 3, 4}) {
      const auto lr = torch::full({2, 3, 5, 7}, 0.37f);
      const auto sr = upscale(lr, scale);
      ASSERT_EQ(sr.sizes(), (std::vector<int64_t>{2, 3, 5 * scale, 7 * scale})) << name;
      EXPECT_LT((sr - 0.37f).abs().max().item<float>(), 1e-5) << name << " x" << scale;
    }
}

TEST(Baselines, TinyInputsStayFinite) {
  for (const auto& [name, upscale] : all_upscalers())
    for (int scale : {2, 3, 4})
      for (int64_t size : {1, 2}) {
        const auto sr = upscale(torch::rand({1, 3, size, size}), scale);
        EXPECT_TRUE(torch::isfinite(sr).all().item<bool>()) << name << " " << size << "px x" << scale;
      }
}

TEST(Baselines, NearestReplicatesPixels) {
  const auto lr = torch::rand({1, 3, 4, 4});
  const auto sr = upscale_nearest(lr, 3);
  EXPECT_TRUE(torch::equal(sr.slice(2, 3, 6).slice(3, 6, 9), lr.slice(2, 1, 2).slice(3, 2, 3).expand({1, 3, 3, 3})));
}

TEST(Baselines, LinearRampsAreReproducedAwayFromTheBorder) {
  // Interpolators that reproduce linear functions must give the ramp at the output centres.
  const int s = 2;
  const auto x = torch::arange(16, torch::kFloat64) / 16.0;
  const auto lr = x.view({1, 1, 1, 16}).expand({1, 3, 8, 16}).contiguous();
  const auto expected = ((torch::arange(32, torch::kFloat64) + 0.5) / s - 0.5) / 16.0;
  const auto bilinear = upscale_bilinear(lr, s)[0][0][4].slice(0, 6, 26);
  EXPECT_LT((bilinear - expected.slice(0, 6, 26)).abs().max().item<double>(), 1e-9);
  // Keys cubic (a = -0.75) and Lanczos reproduce linear functions only approximately.
  const auto bicubic = upscale_bicubic(lr, s)[0][0][4].slice(0, 6, 26);
  EXPECT_LT((bicubic - expected.slice(0, 6, 26)).abs().max().item<double>(), 5e-3);
  const auto lanczos = upscale_lanczos(lr, s)[0][0][4].slice(0, 8, 24);
  EXPECT_LT((lanczos - expected.slice(0, 8, 24)).abs().max().item<double>(), 5e-3);
}

TEST(Baselines, LanczosMatrixRowsSumToOne) {
  const auto m = resampling_matrix(9, 27, 3.0, [](double x) { return std::abs(x) < 3 ? 1.0 - std::abs(x) / 3 : 0.0; });
  EXPECT_LT((m.sum(1) - 1).abs().max().item<double>(), 1e-12);
}

TEST(Fsr1, EasuStaysWithinTheNeighbourhoodAndRcasKeepsRange) {
  torch::manual_seed(1);
  const auto lr = torch::rand({1, 3, 12, 12});
  const auto easu = fsr1_easu(lr, 2);
  EXPECT_GE(easu.min().item<float>(), lr.min().item<float>() - 1e-6);
  EXPECT_LE(easu.max().item<float>(), lr.max().item<float>() + 1e-6);
  const auto rcas = fsr1_rcas(easu, 0.0);
  EXPECT_GE(rcas.min().item<float>(), 0.0f);
  EXPECT_LE(rcas.max().item<float>(), 1.0f);
}

TEST(Fsr1, RcasLeavesFlatRegionsAlone) {
  const auto flat = torch::full({1, 3, 8, 8}, 0.6f);
  EXPECT_LT((fsr1_rcas(flat, 0.0) - flat).abs().max().item<float>(), 1e-6);
}

TEST(Fsr1, SharperEdgesThanBilinear) {
  // Upscaling a rendered step edge: FSR keeps a steeper transition than bilinear and ends
  // closer to the natively rendered high-resolution edge.
  const auto lr = step_edge(16, 16), hr = step_edge(32, 32);
  const auto fsr = upscale_fsr1(lr, 2), bilinear = upscale_bilinear(lr, 2);
  auto max_step = [](const torch::Tensor& img) { return (img.slice(3, 1) - img.slice(3, 0, -1)).abs().max().item<float>(); };
  EXPECT_GT(max_step(fsr), max_step(bilinear));
  EXPECT_LT((fsr - hr).pow(2).mean().item<float>(), (bilinear - hr).pow(2).mean().item<float>());
}

TEST(Fsr1, ClampsSaturatedAndRejectsNonFiniteInput) {
  const auto hot = torch::full({1, 3, 4, 4}, 3.0f);
  EXPECT_LE(upscale_fsr1(hot, 2).max().item<float>(), 1.0f);
  auto nan = torch::rand({1, 3, 4, 4});
  nan[0][1][2][2] = std::nanf("");
  EXPECT_ANY_THROW(upscale_fsr1(nan, 2));
}

// The tests below pin the banded Lanczos to its dense matrix form and to its behaviour on
// extreme input, and check properties every upscaler must have.
namespace {
// Output j of an upscale by `scale` samples the input at this coordinate (DESIGN.md convention).
double sample_coordinate(int64_t j, int scale) { return (j + 0.5) / scale - 0.5; }

double lanczos3(double x) {
  auto sinc = [](double v) { return v == 0 ? 1.0 : std::sin(M_PI * v) / (M_PI * v); };
  return std::abs(x) < 3 ? sinc(x) * sinc(x / 3) : 0.0;
}

double max_abs_diff(const torch::Tensor& a, const torch::Tensor& b) {
  return (a.to(torch::kFloat64) - b.to(torch::kFloat64)).abs().max().item<double>();
}
}  // namespace

TEST(Baselines, LanczosEqualsTheDenseMatrixProduct) {
  torch::manual_seed(2);
  for (auto [h, w] : std::vector<std::pair<int64_t, int64_t>>{{1, 1}, {2, 2}, {1, 4}, {3, 5}, {17, 13}})
    for (int scale : {2, 3, 4}) {
      const auto lr = torch::rand({2, 3, h, w}, torch::kFloat64);
      const auto rows = resampling_matrix(h, h * scale, 3.0, lanczos3);
      const auto cols = resampling_matrix(w, w * scale, 3.0, lanczos3);
      const auto dense = torch::matmul(torch::matmul(rows, lr), cols.t());
      const std::string where = std::to_string(h) + "x" + std::to_string(w) + " x" + std::to_string(scale);
      EXPECT_LT(max_abs_diff(upscale_lanczos(lr, scale), dense), 1e-12) << where;  // double in, double out
      const auto single = upscale_lanczos(lr.to(torch::kFloat32), scale);
      ASSERT_EQ(single.scalar_type(), torch::kFloat32);
      EXPECT_LT(max_abs_diff(single, dense), 1e-5) << where;
    }
}

TEST(Baselines, LanczosIsLinearAndDoesNotClamp) {
  torch::manual_seed(3);
  const auto lr = torch::rand({1, 3, 9, 11});
  EXPECT_EQ(upscale_lanczos(torch::zeros({1, 3, 4, 4}), 3).abs().max().item<float>(), 0.0f);
  EXPECT_LT(max_abs_diff(upscale_lanczos(torch::ones({1, 3, 4, 4}), 3), torch::ones({1, 3, 12, 12})), 1e-6);
  // Values outside [0,1] are not clamped: Lanczos is linear.
  const auto wide = lr * 4 - 1.5;
  EXPECT_LT(max_abs_diff(upscale_lanczos(wide, 2), upscale_lanczos(lr, 2) * 4 - 1.5), 1e-5);
  for (float v : {-0.5f, 2.0f})
    EXPECT_LT(max_abs_diff(upscale_lanczos(torch::full({1, 3, 5, 3}, v), 2), torch::full({1, 3, 10, 6}, v)), 1e-6);
}

TEST(Baselines, LanczosNanReachesOnlyTheOutputsWhoseTapsCoverIt) {
  auto lr = torch::rand({1, 3, 16, 16});
  lr[0][1][8][5] = std::nanf("");
  const auto sr = upscale_lanczos(lr, 2);
  const auto nan = torch::isnan(sr);
  EXPECT_FALSE(nan[0][0].any().item<bool>());
  EXPECT_FALSE(nan[0][2].any().item<bool>());
  EXPECT_TRUE(nan[0][1][16][10].item<bool>());
  const auto mask = nan[0][1];
  for (int64_t y = 0; y < 32; ++y)
    for (int64_t x = 0; x < 32; ++x) {
      const bool covered = std::abs(sample_coordinate(y, 2) - 8) <= 3 && std::abs(sample_coordinate(x, 2) - 5) <= 3;
      if (!covered) {
        ASSERT_FALSE(mask[y][x].item<bool>()) << y << "," << x;
      }
    }
}

TEST(Baselines, TinyInputsGiveTheTexelEverywhere) {
  // A 1x1 image has one texel: every upscaler must spread it unchanged (FSR clamps to [0,1]).
  torch::manual_seed(4);
  const auto lr = torch::rand({2, 3, 1, 1});
  for (const auto& [name, upscale] : all_upscalers())
    for (int scale : {2, 3, 4}) {
      const auto sr = upscale(lr, scale);
      ASSERT_EQ(sr.sizes(), (std::vector<int64_t>{2, 3, scale, scale})) << name;
      EXPECT_LT(max_abs_diff(sr, lr.expand_as(sr)), 1e-6) << name << " x" << scale;
    }
}

TEST(Baselines, BatchItemsAreIndependent) {
  torch::manual_seed(5);
  const auto lr = torch::rand({3, 3, 7, 10});
  for (const auto& [name, upscale] : all_upscalers())
    for (int scale : {2, 3}) {
      const auto batch = upscale(lr, scale);
      for (int64_t i = 0; i < 3; ++i)
        EXPECT_TRUE(torch::equal(batch[i], upscale(lr.slice(0, i, i + 1), scale)[0])) << name << " item " << i;
    }
}
