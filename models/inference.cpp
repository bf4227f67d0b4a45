#include "models/inference.h"

#include <torch/torch.h>

#include "core/error.h"

namespace cgsr {
namespace {
// The forward in one concrete layout; the weights stay as they are (LibTorch's convolutions
// follow the activations' layout).
torch::Tensor forward_in(SRNetworkImpl& net, const torch::Tensor& lr_color, const torch::Tensor& info,
                         MemoryLayout layout) {
  torch::NoGradGuard no_grad;
  net.eval();
  return net.forward(to_layout(lr_color, layout), to_layout(info, layout)).contiguous();
}
}  // namespace

const std::vector<std::string>& EnumNames<InferenceEngine>::names() {
  static const std::vector<std::string> names = {"fused", "libtorch"};
  return names;
}

MemoryLayout inference_layout(SRNetworkImpl& net, const torch::Tensor& lr_color, const torch::Tensor& info,
                              MemoryLayout requested) {
  if (requested != MemoryLayout::Auto) return requested;
  CGSR_CHECK(lr_color.defined() && lr_color.dim() == 4, "inference_layout: colour must be [N, 3, h, w]");
  const int64_t h = std::min<int64_t>(lr_color.size(2), 120), w = std::min<int64_t>(lr_color.size(3), 160);
  const auto color = lr_color.slice(2, 0, h).slice(3, 0, w).contiguous();
  torch::Tensor crop;
  if (info.defined()) {
    const int64_t f = info.size(2) / std::max<int64_t>(1, lr_color.size(2));
    crop = info.slice(2, 0, h * f).slice(3, 0, w * f).contiguous();
  }
  const std::string key = "inference of " + spec_summary(net.spec()) + " on " + std::to_string(lr_color.size(0)) + "x" +
                          std::to_string(w) + "x" + std::to_string(h);
  return measured_layout(key, [&](MemoryLayout layout) { forward_in(net, color, crop, layout); });
}

torch::Tensor infer(SRNetworkImpl& net, const torch::Tensor& lr_color, const torch::Tensor& info,
                    MemoryLayout layout) {
  return forward_in(net, lr_color, info, inference_layout(net, lr_color, info, layout));
}

}  // namespace cgsr
