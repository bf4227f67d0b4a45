#include "core/color.h"

#include "core/error.h"
#include "core/tensor_checks.h"

namespace cgsr {

torch::Tensor srgb_to_linear(const torch::Tensor& srgb) {
  const auto x = srgb.clamp(0.0, 1.0);
  return torch::where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055).pow(2.4));
}

torch::Tensor linear_to_srgb(const torch::Tensor& linear) {
  const auto x = linear.clamp(0.0, 1.0);
  return torch::where(x <= 0.0031308, x * 12.92, 1.055 * x.pow(1.0 / 2.4) - 0.055);
}

torch::Tensor rgb_to_y(const torch::Tensor& rgb) {
  if (rgb.dim() < 3 || rgb.size(-3) != 3)
    throw Error("rgb_to_y", "expected 3 colour channels at dim -3, got shape " + shape_string(rgb));
  const auto r = rgb.select(-3, 0), g = rgb.select(-3, 1), b = rgb.select(-3, 2);
  return (16.0 + 65.481 * r + 128.553 * g + 24.966 * b).div(255.0).unsqueeze(-3);
}

}  // namespace cgsr
