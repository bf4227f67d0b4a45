#pragma once
// The SSIM definition shared by the SSIM metric (metrics.h, float64 loops) and the SSIM training
// loss (train/losses.h, differentiable tensor ops), so the two cannot drift apart: Wang et al.
// 2004 with an 11x11 Gaussian window (sigma 1.5, the outer product of gaussian_1d), K1 0.01,
// K2 0.03, dynamic range L = 1, over the valid region (no padding).

#include <array>
#include <cmath>

namespace cgsr::ssim_window {

constexpr int kSize = 11;
constexpr double kSigma = 1.5;
constexpr double kC1 = 0.01 * 0.01;  // (K1 L)^2
constexpr double kC2 = 0.03 * 0.03;  // (K2 L)^2

// The normalized 1-D Gaussian of the window.
inline std::array<double, kSize> gaussian_1d() {
  std::array<double, kSize> g{};
  double sum = 0;
  for (int k = 0; k < kSize; ++k) {
    const double x = k - (kSize - 1) / 2.0;
    g[k] = std::exp(-(x * x) / (2 * kSigma * kSigma));
    sum += g[k];
  }
  for (double& v : g) v /= sum;
  return g;
}

// SSIM at one position from the window's weighted means (mu), second moments (e_aa, e_bb) and
// cross moment (e_ab). T is double (the metric) or torch::Tensor (the loss, element-wise).
template <class T>
T from_moments(const T& mu_a, const T& mu_b, const T& e_aa, const T& e_bb, const T& e_ab) {
  const T var_a = e_aa - mu_a * mu_a, var_b = e_bb - mu_b * mu_b, cov = e_ab - mu_a * mu_b;
  return ((2 * mu_a * mu_b + kC1) * (2 * cov + kC2)) / ((mu_a * mu_a + mu_b * mu_b + kC1) * (var_a + var_b + kC2));
}

}  // namespace cgsr::ssim_window
