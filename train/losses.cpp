#include "train/losses.h"

#include <torch/torch.h>

#include "core/error.h"
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
  static const std::vector<std::string> names = {"l2", "l1"};
  return names;
}

torch::Tensor reconstruction_error(const torch::Tensor& output, const torch::Tensor& target, ErrorNorm norm) {
  return norm == ErrorNorm::L1 ? torch::l1_loss(output, target) : torch::mse_loss(output, target);
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
