// Classic upscalers: conventions, exactness on simple signals, and FSR's edge behaviour.
#include <gtest/gtest.h>
#include <torch/torch.h>

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
