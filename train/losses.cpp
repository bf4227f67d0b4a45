#include "train/losses.h"

#include <torch/torch.h>

#include <array>

#include "core/error.h"
#include "core/ssim_window.h"
#include "core/tensor_checks.h"
#include "models/importance/channel_importance.h"

namespace cgsr {

config::Schema<LossOptions> loss_schema() {
  config::Schema<LossOptions> s;
  s.field("image_norm", &LossOptions::image_norm, "norm of the image term");
  s.field("geometry_norm", &LossOptions::geometry_norm, "norm of the geometry term");
  s.field("lambda_geometry", &LossOptions::lambda_geometry, "weight of the geometry term (needs a geometry head)")
      .at_least(0);
  s.field("lambda_rit", &LossOptions::lambda_rit, "weight of the L1 norm of the RIT gates").at_least(0);
  s.field("lambda_shrink", &LossOptions::lambda_shrink, "weight of the L1 norm of channels to be removed")
      .at_least(0);
  return s;
}

const std::vector<std::string>& EnumNames<ErrorNorm>::names() {
  static const std::vector<std::string> names = {"l2", "l1", "ssim"};
  return names;
}

torch::Tensor reconstruction_error(const torch::Tensor& output, const torch::Tensor& target, ErrorNorm norm) {
  switch (norm) {
    case ErrorNorm::L1: return torch::l1_loss(output, target);
    case ErrorNorm::Ssim: return ssim_loss(output, target);
    case ErrorNorm::L2: break;
  }
  return torch::mse_loss(output, target);
}

torch::Tensor ssim_loss(const torch::Tensor& output, const torch::Tensor& target) {
  constexpr int64_t k = ssim_window::kSize;
  if (!output.sizes().equals(target.sizes()))
    throw Error("SSIM loss", "shapes differ: " + shape_string(output) + " vs " + shape_string(target));
  if (output.dim() != 3 && output.dim() != 4)
    throw Error("SSIM loss", "expected CHW or NCHW, got shape " + shape_string(output));
  const auto a = output.dim() == 3 ? output.unsqueeze(0) : output;
  const auto b = target.dim() == 3 ? target.unsqueeze(0) : target;
  if (a.size(2) < k || a.size(3) < k)
    throw Error("SSIM loss", "needs images (training patches) of at least 11x11 pixels, got " +
                                 std::to_string(a.size(3)) + "x" + std::to_string(a.size(2)));
  // The five local statistics of every plane as one depthwise convolution: the separable
  // Gaussian window as a column pass, then a row pass (as the metric does), no padding.
  static const std::array<double, k> g = ssim_window::gaussian_1d();
  const auto kernel = torch::tensor(std::vector<double>(g.begin(), g.end()), torch::kFloat64).to(a.scalar_type());
  const int64_t planes = 5 * a.size(1);
  const auto stats = torch::cat({a, b, a * a, b * b, a * b}, 1);
  const auto column = kernel.view({1, 1, k, 1}).repeat({planes, 1, 1, 1});
  const auto row = kernel.view({1, 1, 1, k}).repeat({planes, 1, 1, 1});
  const auto depthwise = [planes](const torch::Tensor& x, const torch::Tensor& w) {
    return torch::conv2d(x, w, torch::Tensor(), torch::IntArrayRef{1, 1}, torch::IntArrayRef{0, 0},
                         torch::IntArrayRef{1, 1}, planes);
  };
  const auto local = depthwise(depthwise(stats, column), row);
  const auto m = local.chunk(5, 1);
  return 1 - ssim_window::from_moments(m[0], m[1], m[2], m[3], m[4]).mean();
}

LossTerms cgsr_loss(const SRNetworkImpl& net, const TrainOutput& output, const Batch& batch,
                    const LossOptions& options, const ShrinkTargets& shrink) {
  LossTerms terms;
  auto total = reconstruction_error(output.image, batch.hr_color, options.image_norm);
  terms.image = total.item<double>();

  if (options.lambda_geometry > 0 && output.geometry.defined()) {
    const auto geometry = reconstruction_error(output.geometry, net.geometry_target(batch), options.geometry_norm);
    terms.geometry = geometry.item<double>();
    total = total + options.lambda_geometry * geometry;
  }
  if (options.lambda_rit > 0 && net.has_rit()) {
    const auto rit = net.rit_gate().abs().sum();
    terms.rit = rit.item<double>();
    total = total + options.lambda_rit * rit;
  }
  if (options.lambda_shrink > 0 && !shrink.empty()) {
    const auto importance = channel_importance(net);
    auto sum = torch::zeros({}, output.image.options());
    for (const auto& [group, channels] : shrink) {
      const auto it = importance.find(group);
      if (it == importance.end()) throw Error("loss", "no prunable layer group '" + group + "' in the network");
      if (channels.empty()) continue;
      sum = sum + it->second.index_select(0, torch::tensor(channels, torch::kLong)).sum();
    }
    terms.shrink = sum.item<double>();
    total = total + options.lambda_shrink * sum;
  }
  terms.total = total;
  return terms;
}

}  // namespace cgsr
