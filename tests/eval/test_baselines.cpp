// Classic upscalers: conventions, exactness on simple signals, and FSR's edge behaviour.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "eval/baselines/fsr1.h"
#include "eval/baselines/interpolation.h"

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

TEST(Baselines, BicubicAtTheJitterIsBicubicOfTheUnjitteredImage) {
  const auto lr = torch::rand({2, 3, 9, 11});
  // No jitter: upscale_bicubic, edges included.
  EXPECT_LT((upscale_bicubic_jittered(lr, 2, {{0, 0}, {0, 0}}) - upscale_bicubic(lr, 2)).abs().max().item<float>(), 1e-5);
  // A frame jittered by a whole LR pixel is the unjittered one shifted: content at p + 1 in x.
  const auto shifted = torch::cat({lr.slice(3, 0, 1), lr.slice(3, 0, 10)}, 3);  // shifted[x] = lr[x - 1]
  const auto at_jitter = upscale_bicubic_jittered(shifted, 2, {{1, 0}, {1, 0}});
  const auto plain = upscale_bicubic(lr, 2);
  // Up to the last 5 output columns, whose taps reach the column the shift dropped, the two agree.
  EXPECT_LT((at_jitter - plain).slice(3, 0, 17).abs().max().item<float>(), 1e-5);
  EXPECT_GT((at_jitter - plain).slice(3, 17).abs().max().item<float>(), 1e-3);
  EXPECT_THROW(upscale_bicubic_jittered(lr, 2, {{0, 0}}), Error);  // one jitter per item
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

// The tests below pin the loop implementations of Lanczos, EASU and RCAS to references computed
// another way (dense matrices, neighbourhood bounds, the two-pass composition) and to their
// behaviour on extreme input.
namespace {
// Output j of an upscale by `scale` samples the input at this coordinate (docs/design.md convention).
double sample_coordinate(int64_t j, int scale) { return (j + 0.5) / scale - 0.5; }

double lanczos3(double x) {
  auto sinc = [](double v) { return v == 0 ? 1.0 : std::sin(M_PI * v) / (M_PI * v); };
  return std::abs(x) < 3 ? sinc(x) * sinc(x / 3) : 0.0;
}

// Per output pixel, the min and max over the four input texels around its sample point.
std::pair<torch::Tensor, torch::Tensor> four_texel_bounds(const torch::Tensor& lr, int scale) {
  auto nearest_two = [&](int64_t in, int64_t out) {
    std::vector<int64_t> lo, hi;
    for (int64_t j = 0; j < out; ++j) {
      const auto i = static_cast<int64_t>(std::floor(sample_coordinate(j, scale)));
      lo.push_back(std::clamp<int64_t>(i, 0, in - 1));
      hi.push_back(std::clamp<int64_t>(i + 1, 0, in - 1));
    }
    return std::pair{torch::tensor(lo), torch::tensor(hi)};
  };
  const auto [y0, y1] = nearest_two(lr.size(2), lr.size(2) * scale);
  const auto [x0, x1] = nearest_two(lr.size(3), lr.size(3) * scale);
  auto at = [&](const torch::Tensor& ys, const torch::Tensor& xs) { return lr.index_select(2, ys).index_select(3, xs); };
  const auto a = at(y0, x0), b = at(y0, x1), c = at(y1, x0), d = at(y1, x1);
  return {torch::minimum(torch::minimum(a, b), torch::minimum(c, d)),
          torch::maximum(torch::maximum(a, b), torch::maximum(c, d))};
}

// A rectangle and a slanted half-plane on a dark background, far enough apart that no 4x4
// neighbourhood sees two opposite edges: horizontal, vertical and slanted edges in RGB.
torch::Tensor shapes(int64_t h, int64_t w) {
  const auto y = torch::arange(h, torch::kFloat32).view({h, 1}), x = torch::arange(w, torch::kFloat32).view({1, w});
  auto v = torch::full({h, w}, 0.15f);
  v = torch::where((y >= 3) & (y < 9) & (x >= 3) & (x < 11), torch::full_like(v, 0.85f), v);
  v = torch::where(x + 2 * y > 2 * h + 4, torch::full_like(v, 0.5f), v);
  return torch::stack({v, 0.8 * v, 1.0 - v}).unsqueeze(0).contiguous();
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

TEST(Fsr1, EasuOutputLiesWithinTheFourNearestTexels) {
  torch::manual_seed(6);
  for (auto [h, w] : std::vector<std::pair<int64_t, int64_t>>{{1, 1}, {2, 2}, {2, 5}, {9, 11}, {24, 16}})
    for (int scale : {2, 3, 4}) {
      const auto lr = torch::rand({2, 3, h, w});
      const auto [lo, hi] = four_texel_bounds(lr, scale);
      const auto sr = fsr1_easu(lr, scale);
      const std::string where = std::to_string(h) + "x" + std::to_string(w) + " x" + std::to_string(scale);
      EXPECT_TRUE((sr >= lo).all().item<bool>()) << where;
      EXPECT_TRUE((sr <= hi).all().item<bool>()) << where;
    }
  // Edges: the kernel is stretched and rotated along them; still bounded.
  const auto lr = shapes(20, 24);
  const auto [lo, hi] = four_texel_bounds(lr, 3);
  const auto sr = fsr1_easu(lr, 3);
  EXPECT_TRUE((sr >= lo).all().item<bool>());
  EXPECT_TRUE((sr <= hi).all().item<bool>());
  // ... and not just bilinear: along the edges the result differs from it.
  EXPECT_GT(max_abs_diff(sr, upscale_bilinear(lr, 3)), 0.01);
}

TEST(Fsr1, EasuCommutesWithTransposition) {
  // The 12-tap pattern and the analysis treat x and y alike, so transposing the input transposes
  // the output (up to rounding): this catches a swapped row/column offset in the tap layout.
  // (Not where the direction is "flat" but the edge length is not, e.g. on a shallow ramp: there
  // the kernel is aligned with x either way.)
  for (int scale : {2, 3, 4}) {
    const auto lr = shapes(20, 24);
    const auto direct = fsr1_easu(lr, scale).transpose(2, 3);
    const auto transposed = fsr1_easu(lr.transpose(2, 3).contiguous(), scale);
    EXPECT_LT(max_abs_diff(direct, transposed), 1e-5) << "x" << scale;
  }
}

TEST(Fsr1, OnePassEqualsEasuThenRcas) {
  // upscale_fsr1 runs RCAS on EASU rows as they are made; it must equal the two separate passes.
  torch::manual_seed(7);
  for (auto [h, w] : std::vector<std::pair<int64_t, int64_t>>{{1, 1}, {2, 2}, {3, 1}, {13, 9}})
    for (int scale : {2, 3, 4})
      for (double stops : {0.0, 0.2, 2.0}) {
        const auto lr = torch::rand({2, 3, h, w});
        const auto two_pass = fsr1_rcas(fsr1_easu(lr, scale), stops);
        EXPECT_TRUE(torch::equal(upscale_fsr1(lr, scale, {stops, true}), two_pass))
            << h << "x" << w << " x" << scale << " stops " << stops;
      }
  const auto lr = torch::rand({1, 3, 5, 5});
  EXPECT_TRUE(torch::equal(upscale_fsr1(lr, 2, {0.2, false}), fsr1_easu(lr, 2)));
}

TEST(Fsr1, RcasSharpensWithinRangeAndWeakensWithStops) {
  // A bright dot on grey: RCAS raises the dot and darkens its neighbours, less with more stops,
  // and not at all in the limit.
  auto img = torch::full({1, 3, 7, 7}, 0.4f);
  img.slice(2, 3, 4).slice(3, 3, 4).fill_(0.6f);
  const auto strong = fsr1_rcas(img, 0.0), weak = fsr1_rcas(img, 2.0), off = fsr1_rcas(img, 100.0);
  EXPECT_GT(strong[0][0][3][3].item<float>(), weak[0][0][3][3].item<float>());
  EXPECT_GT(weak[0][0][3][3].item<float>(), 0.6f);
  EXPECT_LT(strong[0][0][3][2].item<float>(), weak[0][0][3][2].item<float>());
  EXPECT_LT(weak[0][0][3][2].item<float>(), 0.4f);
  EXPECT_NEAR(strong[0][0][0][0].item<float>(), 0.4f, 1e-6);  // far from the dot: flat
  EXPECT_LT(max_abs_diff(off, img), 1e-6);
  // Symmetric: the cross treats left/right and up/down alike.
  torch::manual_seed(8);
  const auto r = torch::rand({2, 3, 6, 9});
  EXPECT_LT(max_abs_diff(fsr1_rcas(r.flip(3), 0.0), fsr1_rcas(r, 0.0).flip(3)), 1e-6);
  EXPECT_LT(max_abs_diff(fsr1_rcas(r.transpose(2, 3), 0.0), fsr1_rcas(r, 0.0).transpose(2, 3)), 1e-6);
}

TEST(Fsr1, ExtremeInputs) {
  torch::manual_seed(9);
  for (int scale : {2, 3}) {
    EXPECT_EQ(upscale_fsr1(torch::zeros({1, 3, 6, 5}), scale).abs().max().item<float>(), 0.0f);
    EXPECT_LT(max_abs_diff(upscale_fsr1(torch::ones({1, 3, 6, 5}), scale), torch::ones({1, 3, 6 * scale, 5 * scale})),
              1e-6);
    // Out of range values are clamped first: the same result as clamping them yourself.
    const auto wide = torch::rand({2, 3, 6, 5}) * 3 - 1;
    const auto sr = upscale_fsr1(wide, scale);
    EXPECT_TRUE(torch::equal(sr, upscale_fsr1(wide.clamp(0, 1), scale)));
    EXPECT_GE(sr.min().item<float>(), 0.0f);
    EXPECT_LE(sr.max().item<float>(), 1.0f);
    EXPECT_TRUE(torch::equal(fsr1_rcas(wide, 0.2), fsr1_rcas(wide.clamp(0, 1), 0.2)));
  }
  // Double in, double out, agreeing with the float computation.
  const auto lr = torch::rand({1, 3, 8, 8}, torch::kFloat64);
  const auto sr = upscale_fsr1(lr, 2);
  EXPECT_EQ(sr.scalar_type(), torch::kFloat64);
  EXPECT_LT(max_abs_diff(sr, upscale_fsr1(lr.to(torch::kFloat32), 2)), 1e-5);
  // Non-finite input: EASU (and so the whole upscaler) rejects it.
  auto inf = torch::rand({1, 3, 4, 4});
  inf[0][0][1][1] = std::numeric_limits<float>::infinity();
  EXPECT_ANY_THROW(fsr1_easu(inf, 2));
  EXPECT_ANY_THROW(upscale_fsr1(inf, 2));
}

TEST(Fsr1, RcasNanStaysOnItsCross) {
  auto img = torch::rand({1, 3, 6, 6});
  img[0][1][2][3] = std::nanf("");
  const auto out = fsr1_rcas(img, 0.2);
  const auto nan = torch::isnan(out);
  for (auto [y, x] : std::vector<std::pair<int, int>>{{2, 3}, {1, 3}, {3, 3}, {2, 2}, {2, 4}})
    EXPECT_TRUE(nan[0][1][y][x].item<bool>()) << y << "," << x;
  auto cross = torch::zeros({6, 6}, torch::kBool);
  for (auto [y, x] : std::vector<std::pair<int, int>>{{2, 3}, {1, 3}, {3, 3}, {2, 2}, {2, 4}}) cross[y][x] = true;
  EXPECT_FALSE((nan[0] & ~cross).any().item<bool>());
}
