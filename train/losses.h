#pragma once
// The CGSR training objective (Eq. 1 of the paper, with the weights made explicit):
//   L_t = ||HR - SR|| + lambda_g ||HR_r - SR_r|| + lambda_r sum_i ||R_i||_1 + lambda_s sum_k ||S_k||_1
// image and geometry terms are mean squared (L2, default) or mean absolute (L1) errors, or the
// SSIM loss 1 - mean SSIM (SRPO's objective; the same window and constants as the SSIM metric,
// core/ssim_window.h); R_i are
// the RIT gates; S_k the channels a search candidate is about to remove (their per-channel L1
// importance), so they fade before they are cut. A zero weight disables its term.

#include <torch/types.h>

#include <map>
#include <string>
#include <vector>

#include "core/config.h"
#include "models/sr_network.h"
#include "render_data/batch.h"

namespace cgsr {

// Mean squared (l2) or mean absolute (l1) error, or 1 - mean SSIM (ssim).
enum class ErrorNorm { L2, L1, Ssim };
template <>
struct EnumNames<ErrorNorm> {
  static constexpr const char* kind = "error norm";
  static const std::vector<std::string>& names();
};

struct LossOptions {
  ErrorNorm image_norm = ErrorNorm::L2;
  ErrorNorm geometry_norm = ErrorNorm::L2;
  double lambda_geometry = 0.1;
  double lambda_rit = 1e-4;
  double lambda_shrink = 1e-4;
};
config::Schema<LossOptions> loss_schema();

// Channels to fade, per layer group (indices into the group's channels).
using ShrinkTargets = std::map<std::string, std::vector<int64_t>>;

struct LossTerms {
  torch::Tensor total;  // differentiable scalar
  double image = 0, geometry = 0, rit = 0, shrink = 0;
};

LossTerms cgsr_loss(const SRNetworkImpl& net, const TrainOutput& output, const Batch& batch,
                    const LossOptions& options, const ShrinkTargets& shrink = {});

// Mean squared (l2) or mean absolute (l1) error, or ssim_loss.
torch::Tensor reconstruction_error(const torch::Tensor& output, const torch::Tensor& target, ErrorNorm norm);

// 1 - mean SSIM of NCHW (or CHW) images, differentiable: the metric's ssim() (core/metrics.h)
// as tensor operations, so 1 - ssim(a, b).mean() up to float rounding (computed in the inputs'
// type). The mean runs over every image, channel and valid window position; images need at least
// 11x11 pixels (a cgsr::Error otherwise).
torch::Tensor ssim_loss(const torch::Tensor& output, const torch::Tensor& target);

}  // namespace cgsr
