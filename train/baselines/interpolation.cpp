#include "train/baselines/interpolation.h"

#include <torch/torch.h>

#include <cmath>

#include "core/error.h"
#include "core/tensor_checks.h"

namespace cgsr {
namespace F = torch::nn::functional;

namespace {
void check_input(const torch::Tensor& lr, int scale) {
  if (lr.dim() != 4) throw Error("upscale", "expected NCHW, got " + shape_string(lr));
  if (scale < 1) throw Error("upscale", "scale must be >= 1");
}

double sinc(double x) {
  if (std::abs(x) < 1e-12) return 1.0;
  const double px = M_PI * x;
  return std::sin(px) / px;
}
}  // namespace

torch::Tensor upscale_nearest(const torch::Tensor& lr, int scale) {
  check_input(lr, scale);
  // For an integer scale, each output pixel centre falls inside exactly one input pixel.
  return lr.repeat_interleave(scale, 2).repeat_interleave(scale, 3);
}

torch::Tensor upscale_bilinear(const torch::Tensor& lr, int scale) {
  check_input(lr, scale);
  return F::interpolate(lr, F::InterpolateFuncOptions()
                                .size(std::vector<int64_t>{lr.size(2) * scale, lr.size(3) * scale})
                                .mode(torch::kBilinear)
                                .align_corners(false));
}

torch::Tensor upscale_bicubic(const torch::Tensor& lr, int scale) {
  check_input(lr, scale);
  return F::interpolate(lr, F::InterpolateFuncOptions()
                                .size(std::vector<int64_t>{lr.size(2) * scale, lr.size(3) * scale})
                                .mode(torch::kBicubic)
                                .align_corners(false));
}

torch::Tensor resampling_matrix(int64_t in_size, int64_t out_size, double support,
                                const std::function<double(double)>& kernel) {
  auto m = torch::zeros({out_size, in_size}, torch::kFloat64);
  auto a = m.accessor<double, 2>();
  const double ratio = static_cast<double>(in_size) / static_cast<double>(out_size);
  for (int64_t j = 0; j < out_size; ++j) {
    const double centre = (j + 0.5) * ratio - 0.5;  // input coordinate of this output sample
    const int64_t first = static_cast<int64_t>(std::floor(centre - support)) + 1;
    const int64_t last = static_cast<int64_t>(std::floor(centre + support));
    double total = 0;
    for (int64_t i = first; i <= last; ++i) {
      const double w = kernel(centre - static_cast<double>(i));
      const int64_t clamped = std::clamp<int64_t>(i, 0, in_size - 1);  // replicate the edge
      a[j][clamped] += w;
      total += w;
    }
    for (int64_t i = 0; i < in_size; ++i) a[j][i] /= total;
  }
  return m;
}

torch::Tensor upscale_lanczos(const torch::Tensor& lr, int scale, int lobes) {
  check_input(lr, scale);
  const double n = lobes;
  auto kernel = [n](double x) { return std::abs(x) < n ? sinc(x) * sinc(x / n) : 0.0; };
  const auto rows = resampling_matrix(lr.size(2), lr.size(2) * scale, n, kernel).to(lr.scalar_type());
  const auto cols = resampling_matrix(lr.size(3), lr.size(3) * scale, n, kernel).to(lr.scalar_type());
  // out[n,c] = rows @ lr[n,c] @ cols^T
  return torch::matmul(torch::matmul(rows, lr), cols.t());
}

}  // namespace cgsr
