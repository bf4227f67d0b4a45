// PSNR (plain and masked) and SSIM against independently derived values.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cmath>

#include "core/error.h"
#include "core/metrics.h"

using namespace cgsr;

namespace {
torch::Tensor constant(double value, int64_t c = 3, int64_t h = 16, int64_t w = 16) {
  return torch::full({1, c, h, w}, value, torch::kFloat64);
}

// SSIM of one window, computed directly from the definition with explicit loops (no convolution).
double ssim_single_window(const torch::Tensor& a, const torch::Tensor& b) {
  const int n = 11;
  double g[11], total = 0;
  for (int i = 0; i < n; ++i) total += g[i] = std::exp(-std::pow(i - 5, 2) / (2 * 1.5 * 1.5));
  auto A = a.to(torch::kFloat64).contiguous(), B = b.to(torch::kFloat64).contiguous();
  auto pa = A.accessor<double, 2>(), pb = B.accessor<double, 2>();
  double ma = 0, mb = 0, saa = 0, sbb = 0, sab = 0;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const double w = g[y] * g[x] / (total * total);
      ma += w * pa[y][x];
      mb += w * pb[y][x];
      saa += w * pa[y][x] * pa[y][x];
      sbb += w * pb[y][x] * pb[y][x];
      sab += w * pa[y][x] * pb[y][x];
    }
  const double va = saa - ma * ma, vb = sbb - mb * mb, cov = sab - ma * mb;
  const double c1 = 1e-4, c2 = 9e-4;
  return (2 * ma * mb + c1) * (2 * cov + c2) / ((ma * ma + mb * mb + c1) * (va + vb + c2));
}
}  // namespace

TEST(Psnr, ConstantOffsetGivesTwentyDecibels) {
  // MSE = 0.1^2 = 0.01 -> 10 log10(1 / 0.01) = 20 dB.
  EXPECT_NEAR(psnr(constant(0.5), constant(0.6)).item<double>(), 20.0, 1e-5);
}

TEST(Psnr, KnownNoiseVariance) {
  // A +-sigma checkerboard has MSE sigma^2 exactly, whatever its layout.
  const double sigma = 0.05;
  auto reference = torch::rand({1, 3, 32, 32}, torch::kFloat64) * 0.8 + 0.1;
  auto sign = (torch::arange(32 * 32).reshape({32, 32}).remainder(2) * 2 - 1).to(torch::kFloat64);
  auto noisy = reference + sigma * sign;
  EXPECT_NEAR(psnr(noisy, reference).item<double>(), -10 * std::log10(sigma * sigma), 1e-9);
}

TEST(Psnr, IdenticalImagesAreInfiniteAndJsonSafe) {
  auto image = torch::rand({2, 3, 8, 8});
  const auto values = psnr(image, image);
  EXPECT_TRUE(std::isinf(values[0].item<double>()));
  nlohmann::ordered_json j;
  put_psnr(j, "psnr", values[0].item<double>());
  EXPECT_TRUE(j["psnr"].is_null());
  EXPECT_TRUE(j["psnr_infinite"].get<bool>());
  EXPECT_NO_THROW(j.dump());
}

TEST(Psnr, OnePerImageInABatch) {
  auto reference = torch::zeros({2, 3, 8, 8});
  auto output = reference.clone();
  output[0].fill_(0.1);  // 20 dB
  output[1].fill_(0.01); // 40 dB
  const auto values = psnr(output, reference);
  ASSERT_EQ(values.size(0), 2);
  EXPECT_NEAR(values[0].item<double>(), 20.0, 1e-4);
  EXPECT_NEAR(values[1].item<double>(), 40.0, 1e-4);
}

TEST(Psnr, YChannelOfGreyImages) {
  // For R = G = B, Y differs by delta * 219/255 (BT.601 studio range).
  const double delta = 0.1;
  const double expected = -10 * std::log10(std::pow(delta * 219.0 / 255.0, 2));
  QualityOptions y;
  y.y_channel = true;
  EXPECT_NEAR(psnr(constant(0.3), constant(0.3 + delta), y).item<double>(), expected, 1e-4);
}

TEST(Psnr, BorderCropIgnoresTheBorder) {
  auto reference = torch::zeros({1, 3, 12, 12});
  auto output = reference.clone();
  output.slice(2, 0, 2).fill_(1.0);  // only the top two rows differ
  QualityOptions crop;
  crop.crop_border = 2;
  EXPECT_TRUE(std::isinf(psnr(output, reference, crop).item<double>()));
  EXPECT_FALSE(std::isinf(psnr(output, reference).item<double>()));
}

TEST(Psnr, RejectsBadInput) {
  auto good = torch::rand({1, 3, 8, 8});
  auto bad = good.clone();
  bad[0][0][0][0] = std::nan("");
  EXPECT_THROW(psnr(bad, good), Error);
  bad[0][0][0][0] = INFINITY;
  EXPECT_THROW(psnr(good, bad), Error);
  EXPECT_THROW(psnr(good, torch::rand({1, 3, 8, 9})), Error);
  QualityOptions crop;
  crop.crop_border = 4;
  EXPECT_THROW(psnr(good, good, crop), Error);
}

TEST(MaskedPsnr, AllTrueMaskIsThePlainPsnr) {
  torch::manual_seed(5);
  auto reference = torch::rand({2, 3, 20, 24});
  auto output = (reference + 0.05 * torch::randn_like(reference)).clamp(0, 1);
  for (const bool y : {false, true})
    for (const int crop : {0, 3}) {
      SCOPED_TRACE(std::to_string(y) + " " + std::to_string(crop));
      QualityOptions o;
      o.y_channel = y;
      o.crop_border = crop;
      const auto plain = psnr(output, reference, o);
      const auto masked = masked_psnr(output, reference, torch::ones({20, 24}, torch::kBool), o);
      ASSERT_EQ(masked.size(), 2u);
      for (int i = 0; i < 2; ++i) {
        ASSERT_TRUE(masked[i].inside.has_value());
        EXPECT_NEAR(*masked[i].inside, plain[i].item<double>(), 1e-9);
        EXPECT_FALSE(masked[i].outside.has_value());
        EXPECT_EQ(masked[i].inside_fraction, 1.0);
      }
    }
}

TEST(MaskedPsnr, MatchesAHandComputation) {
  // 2x2 pixels, 3 channels. Inside: the top row; (0,0) is off by 0.1 in every channel and (0,1)
  // by 0.2 in the red channel: MSE = (3 * 0.01 + 0.04) / 6. Outside: (1,1) is off by 0.5 in
  // blue: MSE = 0.25 / 6.
  auto reference = torch::zeros({1, 3, 2, 2}, torch::kFloat64);
  auto output = reference.clone();
  output.index_put_({0, torch::indexing::Slice(), 0, 0}, 0.1);
  output.index_put_({0, 0, 0, 1}, 0.2);
  output.index_put_({0, 2, 1, 1}, 0.5);
  auto mask = torch::tensor({1, 1, 0, 0}, torch::kUInt8).view({1, 2, 2});
  const auto m = masked_psnr(output, reference, mask).at(0);
  ASSERT_TRUE(m.inside && m.outside);
  EXPECT_NEAR(*m.inside, -10 * std::log10(0.07 / 6), 1e-9);
  EXPECT_NEAR(*m.outside, -10 * std::log10(0.25 / 6), 1e-9);
  EXPECT_EQ(m.inside_fraction, 0.5);
}

TEST(MaskedPsnr, EmptySideHasNoValueAndAnExactSideIsInfinite) {
  torch::manual_seed(6);
  auto reference = torch::rand({1, 3, 10, 10});
  auto output = reference.clone();
  output.slice(2, 5, 10).add_(0.1);  // only the bottom half differs
  auto nothing = torch::zeros({10, 10}, torch::kBool);
  const auto none = masked_psnr(output, reference, nothing).at(0);
  EXPECT_FALSE(none.inside.has_value());
  ASSERT_TRUE(none.outside.has_value());
  EXPECT_NEAR(*none.outside, psnr(output, reference).item<double>(), 1e-9);
  EXPECT_EQ(none.inside_fraction, 0.0);

  // Only border pixels selected: nothing is left inside once the border is cropped.
  auto border = torch::ones({10, 10}, torch::kBool);
  border.slice(0, 2, 8).slice(1, 2, 8).fill_(false);
  QualityOptions crop;
  crop.crop_border = 2;
  EXPECT_FALSE(masked_psnr(output, reference, border, crop).at(0).inside.has_value());
  EXPECT_TRUE(masked_psnr(output, reference, border).at(0).inside.has_value());

  auto top = torch::zeros({10, 10}, torch::kBool);
  top.slice(0, 0, 5).fill_(true);
  const auto split = masked_psnr(output, reference, top).at(0);
  ASSERT_TRUE(split.inside && split.outside);
  EXPECT_TRUE(std::isinf(*split.inside) && *split.inside > 0);
  EXPECT_NEAR(*split.outside, 20.0, 1e-4);  // an offset of 0.1 everywhere outside
}

TEST(MaskedPsnr, RejectsBadMasksAndNonFiniteInputAnywhere) {
  auto good = torch::rand({1, 3, 8, 8});
  auto mask = torch::ones({8, 8}, torch::kBool);
  EXPECT_THROW(masked_psnr(good, good, torch::ones({8, 9}, torch::kBool)), Error);
  EXPECT_THROW(masked_psnr(good, good, torch::ones({2, 8, 8}, torch::kBool)), Error);
  EXPECT_THROW(masked_psnr(good, good, torch::ones({8, 8}, torch::kFloat32)), Error);
  auto bad = good.clone();
  bad[0][1][7][7] = std::nan("");
  mask[7][7] = false;  // the NaN is outside the mask: still an error
  EXPECT_THROW(masked_psnr(bad, good, mask), Error);
}

TEST(Ssim, IdenticalImagesScoreOne) {
  auto image = torch::rand({1, 3, 20, 20});
  EXPECT_NEAR(ssim(image, image).item<double>(), 1.0, 1e-12);
}

TEST(Ssim, ConstantImagesHaveTheClosedForm) {
  // No variance: SSIM = (2 a b + C1) / (a^2 + b^2 + C1).
  const double a = 0.2, b = 0.7, c1 = 1e-4;
  EXPECT_NEAR(ssim(constant(a), constant(b)).item<double>(), (2 * a * b + c1) / (a * a + b * b + c1), 1e-9);
}

TEST(Ssim, MatchesADirectComputationOnOneWindow) {
  torch::manual_seed(3);
  auto a = torch::rand({11, 11}, torch::kFloat64);
  auto b = (a + 0.2 * torch::rand({11, 11}, torch::kFloat64)).clamp(0, 1);
  const double expected = ssim_single_window(a, b);
  EXPECT_NEAR(ssim(a.view({1, 1, 11, 11}), b.view({1, 1, 11, 11})).item<double>(), expected, 1e-10);
}

TEST(Ssim, SymmetricBoundedAndFallsWithNoise) {
  torch::manual_seed(4);
  auto image = torch::rand({1, 3, 24, 24});
  auto slightly = (image + 0.02 * torch::randn_like(image)).clamp(0, 1);
  auto very = (image + 0.3 * torch::randn_like(image)).clamp(0, 1);
  const double s1 = ssim(slightly, image).item<double>();
  EXPECT_NEAR(s1, ssim(image, slightly).item<double>(), 1e-12);
  EXPECT_GT(s1, ssim(very, image).item<double>());
  EXPECT_LE(s1, 1.0);
  EXPECT_GE(ssim(very, image).item<double>(), -1.0);
}

TEST(Ssim, RejectsImagesSmallerThanTheWindow) {
  auto small = torch::rand({1, 3, 10, 10});
  EXPECT_THROW(ssim(small, small), Error);
}
