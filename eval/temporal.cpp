#include "eval/temporal.h"

#include <torch/torch.h>

#include "core/error.h"
#include "core/tensor_checks.h"

namespace cgsr {

Warped warp_previous(const torch::Tensor& previous, const torch::Tensor& motion) {
  if (previous.dim() != 4 || motion.dim() != 4 || motion.size(1) != 2 || previous.size(0) != motion.size(0) ||
      previous.size(2) != motion.size(2) || previous.size(3) != motion.size(3))
    throw Error("warp", "image " + shape_string(previous) + " and motion " + shape_string(motion) + " do not match");
  const int64_t h = previous.size(2), w = previous.size(3);
  const auto opts = motion.options();
  // Pixel-centre coordinates of the current frame, then where each pixel was.
  const auto ys = torch::arange(h, opts).view({1, h, 1}).expand({motion.size(0), h, w});
  const auto xs = torch::arange(w, opts).view({1, 1, w}).expand({motion.size(0), h, w});
  const auto src_x = xs + motion.select(1, 0), src_y = ys + motion.select(1, 1);
  // grid_sample with align_corners=false: -1 and 1 are the outer edges of the border pixels.
  const auto grid = torch::stack({(src_x + 0.5) / w * 2 - 1, (src_y + 0.5) / h * 2 - 1}, -1);
  namespace F = torch::nn::functional;
  Warped out;
  out.image = F::grid_sample(previous, grid.to(previous.scalar_type()),
                             F::GridSampleFuncOptions().mode(torch::kBilinear).padding_mode(torch::kBorder).align_corners(false));
  out.valid = ((src_x >= -0.5) & (src_x <= w - 0.5) & (src_y >= -0.5) & (src_y <= h - 0.5)).unsqueeze(1);
  return out;
}

double warping_error(const torch::Tensor& current, const torch::Tensor& previous, const torch::Tensor& motion) {
  const auto warped = warp_previous(previous, motion);
  const auto mask = warped.valid.to(current.scalar_type()).expand_as(current);
  const double count = mask.sum().item<double>();
  if (count == 0) return 0.0;
  return ((current - warped.image).abs() * mask).sum().item<double>() / count;
}

}  // namespace cgsr
