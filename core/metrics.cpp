#include "core/metrics.h"

#include <cmath>

#include "core/color.h"
#include "core/error.h"
#include "core/tensor_checks.h"

namespace cgsr {
namespace {
constexpr int kWindow = 11;
constexpr double kSigma = 1.5;

// Validates the pair and returns both as float64 NCHW after the Y conversion and border crop.
std::pair<torch::Tensor, torch::Tensor> prepare(const torch::Tensor& output, const torch::Tensor& reference,
                                                const QualityOptions& options, const char* metric) {
  if (!output.sizes().equals(reference.sizes()))
    throw Error(metric, "shapes differ: " + shape_string(output) + " vs " + shape_string(reference));
  if (output.dim() != 3 && output.dim() != 4)
    throw Error(metric, "expected CHW or NCHW, got shape " + shape_string(output));
  require_finite(output, std::string(metric) + " input (output image)");
  require_finite(reference, std::string(metric) + " input (reference image)");
  auto a = (output.dim() == 3 ? output.unsqueeze(0) : output).to(torch::kFloat64);
  auto b = (reference.dim() == 3 ? reference.unsqueeze(0) : reference).to(torch::kFloat64);
  if (options.y_channel) {
    a = rgb_to_y(a);
    b = rgb_to_y(b);
  }
  const int64_t crop = options.crop_border;
  if (crop < 0) throw Error(metric, "crop_border must be >= 0");
  if (crop > 0) {
    if (a.size(2) <= 2 * crop || a.size(3) <= 2 * crop)
      throw Error(metric, "crop_border " + std::to_string(crop) + " leaves nothing of a " +
                              std::to_string(a.size(3)) + "x" + std::to_string(a.size(2)) + " image");
    a = a.slice(2, crop, a.size(2) - crop).slice(3, crop, a.size(3) - crop);
    b = b.slice(2, crop, b.size(2) - crop).slice(3, crop, b.size(3) - crop);
  }
  return {a, b};
}

// The normalized 1-D Gaussian; the 11x11 window is its outer product, applied as a row pass and
// a column pass (22 instead of 121 multiply-adds per pixel: float64 convolutions are slow).
torch::Tensor gaussian_1d() {
  auto x = torch::arange(kWindow, torch::kFloat64) - (kWindow - 1) / 2.0;
  auto g = torch::exp(-(x * x) / (2 * kSigma * kSigma));
  return g / g.sum();
}
}  // namespace

torch::Tensor psnr(const torch::Tensor& output, const torch::Tensor& reference, const QualityOptions& options) {
  auto [a, b] = prepare(output, reference, options, "PSNR");
  const auto mse = (a - b).pow(2).mean({1, 2, 3});
  return -10.0 * torch::log10(mse);  // mse = 0 gives +inf
}

torch::Tensor ssim(const torch::Tensor& output, const torch::Tensor& reference, const QualityOptions& options) {
  auto [a, b] = prepare(output, reference, options, "SSIM");
  if (a.size(2) < kWindow || a.size(3) < kWindow)
    throw Error("SSIM", "needs images of at least 11x11 pixels (after cropping), got " + std::to_string(a.size(3)) +
                            "x" + std::to_string(a.size(2)));
  const int64_t c = a.size(1);
  // The five local statistics (means, second moments, cross moment) of every channel in one
  // grouped, separable Gaussian filter over the valid region.
  const auto moments = torch::cat({a, b, a * a, b * b, a * b}, 1);
  const int64_t groups = moments.size(1);
  const auto g = gaussian_1d();
  namespace F = torch::nn::functional;
  const auto rows = F::conv2d(moments, g.view({1, 1, 1, kWindow}).expand({groups, 1, 1, kWindow}).contiguous(),
                              F::Conv2dFuncOptions().groups(groups));
  const auto local = F::conv2d(rows, g.view({1, 1, kWindow, 1}).expand({groups, 1, kWindow, 1}).contiguous(),
                               F::Conv2dFuncOptions().groups(groups));
  const auto stats = local.split(c, 1);
  const auto &mu_a = stats[0], &mu_b = stats[1];
  const double c1 = 0.01 * 0.01, c2 = 0.03 * 0.03;
  const auto var_a = stats[2] - mu_a * mu_a;
  const auto var_b = stats[3] - mu_b * mu_b;
  const auto cov = stats[4] - mu_a * mu_b;
  const auto map = ((2 * mu_a * mu_b + c1) * (2 * cov + c2)) / ((mu_a * mu_a + mu_b * mu_b + c1) * (var_a + var_b + c2));
  return map.mean({1, 2, 3});
}

void put_psnr(nlohmann::ordered_json& j, const std::string& key, double value) {
  if (std::isinf(value) && value > 0) {
    j[key] = nullptr;
    j[key + "_infinite"] = true;
  } else {
    j[key] = value;
  }
}

}  // namespace cgsr
