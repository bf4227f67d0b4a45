#include "models/importance/importance_methods.h"

#include <torch/torch.h>

#include "core/error.h"
#include "models/importance/activation_importance.h"

namespace cgsr {

FrameImportance magnitude_importance(const SRNetworkImpl& net, const std::vector<std::string>& groups) {
  torch::NoGradGuard no_grad;
  const auto all = channel_importance(net);
  FrameImportance out;
  for (const auto& g : groups) {
    const auto it = all.find(g);
    CGSR_CHECK(it != all.end(), "magnitude importance: no weights produce layer group " + g);
    out[g] = it->second.detach().to(torch::kFloat).contiguous();
  }
  return out;
}

const Registry<ImportanceMethod>& importance_methods() {
  static const Registry<ImportanceMethod> registry = [] {
    Registry<ImportanceMethod> r("importance method");
    r.add(
        "taylor",
        {[](SRNetworkImpl& net, const Batch& b, const std::vector<std::string>& g) {
           return frame_importance(net, b, g, ActivationScore::Taylor);
         },
         /*same_on_every_frame=*/false, /*baseline_name=*/""},
        "|activation x gradient of the reconstruction loss| per channel on the frame");
    r.add(
        "activation",
        {[](SRNetworkImpl& net, const Batch& b, const std::vector<std::string>& g) {
           return frame_importance(net, b, g, ActivationScore::MeanAbsolute);
         },
         /*same_on_every_frame=*/false, /*baseline_name=*/""},
        "mean |activation| per channel on the frame");
    r.add(
        "magnitude",
        {[](SRNetworkImpl& net, const Batch&, const std::vector<std::string>& g) { return magnitude_importance(net, g); },
         /*same_on_every_frame=*/true, /*baseline_name=*/"MMP"},
        "L1 norm of the weights producing the channel (the same on every frame)");
    return r;
  }();
  return registry;
}

}  // namespace cgsr
