#include "eval/baselines/history_fill.h"

#include <torch/torch.h>

#include "core/error.h"
#include "core/tensor_checks.h"
#include "eval/baselines/interpolation.h"

namespace cgsr {

torch::Tensor upscale_history_fill(const torch::Tensor& lr, const torch::Tensor& history, int scale,
                                   const std::vector<std::array<double, 2>>& jitter) {
  if (lr.dim() != 4 || lr.size(1) != 3) throw Error("history", "the LR colour must be [N,3,h,w], got " + shape_string(lr));
  if (!history.defined() || history.dim() != 4 || history.size(0) != lr.size(0) || history.size(1) != 4 ||
      history.size(2) != lr.size(2) * scale || history.size(3) != lr.size(3) * scale)
    throw Error("history", "the history channel must be [" + std::to_string(lr.size(0)) + ",4," +
                               std::to_string(lr.size(2) * scale) + "," + std::to_string(lr.size(3) * scale) +
                               "] for this LR colour, got " + shape_string(history));
  const auto sampled = history.narrow(1, 3, 1) > 0;
  const auto elsewhere = jitter.empty() ? upscale_bicubic(lr, scale) : upscale_bicubic_jittered(lr, scale, jitter);
  return torch::where(sampled, history.narrow(1, 0, 3).to(torch::kFloat32), elsewhere);
}

}  // namespace cgsr
