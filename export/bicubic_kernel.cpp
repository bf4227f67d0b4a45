#include "export/bicubic_kernel.h"

#include <torch/torch.h>

#include <cmath>

#include "core/error.h"

namespace cgsr {
namespace {
// Keys' cubic convolution kernel with parameter a.
double cubic_weight(double x) {
  const double a = kBicubicA;
  x = std::abs(x);
  if (x <= 1) return ((a + 2) * x - (a + 3)) * x * x + 1;
  if (x < 2) return ((a * x - 5 * a) * x + 8 * a) * x - 4 * a;
  return 0;
}
}  // namespace

torch::Tensor bicubic_phase_taps(int64_t factor, int64_t phase) {
  CGSR_CHECK(factor >= 1 && phase >= 0 && phase < factor, "bicubic phase out of range");
  const double d = (phase + 0.5) / static_cast<double>(factor) - 0.5;
  const double base = std::floor(d), t = d - base;
  auto taps = torch::zeros({2 * kBicubicPhaseRadius + 1}, torch::kDouble);
  auto acc = taps.accessor<double, 1>();
  for (int64_t k = -1; k <= 2; ++k) {
    const int64_t offset = static_cast<int64_t>(base) + k;  // in [-2, 2]
    CGSR_CHECK(std::abs(offset) <= kBicubicPhaseRadius, "bicubic tap outside the kernel");
    acc[offset + kBicubicPhaseRadius] += cubic_weight(t - k);
  }
  return taps;
}

torch::Tensor bicubic_phase_kernels(int64_t factor) {
  const int64_t size = 2 * kBicubicPhaseRadius + 1;
  auto kernels = torch::empty({factor * factor, 1, size, size}, torch::kDouble);
  for (int64_t py = 0; py < factor; ++py)
    for (int64_t px = 0; px < factor; ++px)
      kernels[py * factor + px][0] = torch::outer(bicubic_phase_taps(factor, py), bicubic_phase_taps(factor, px));
  return kernels.to(torch::kFloat);
}

}  // namespace cgsr
