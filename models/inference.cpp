#include "models/inference.h"

#include <torch/torch.h>

#include "core/error.h"

namespace cgsr {

bool prefers_channels_last(const ArchSpec& spec) {
  (void)spec;
  return false;
}

MemoryLayout memory_layout_from_name(const std::string& name) {
  if (name == "auto") return MemoryLayout::Auto;
  if (name == "nchw") return MemoryLayout::Nchw;
  if (name == "nhwc") return MemoryLayout::Nhwc;
  throw Error("memory layout", "'" + name + "' is not one of: auto, nchw, nhwc");
}

const char* memory_layout_name(MemoryLayout layout) {
  switch (layout) {
    case MemoryLayout::Auto: return "auto";
    case MemoryLayout::Nchw: return "nchw";
    case MemoryLayout::Nhwc: return "nhwc";
  }
  return "?";
}

torch::Tensor infer(SRNetworkImpl& net, const torch::Tensor& lr_color, const torch::Tensor& info,
                    MemoryLayout layout) {
  torch::NoGradGuard no_grad;
  net.eval();
  const bool nhwc_layout =
      layout == MemoryLayout::Nhwc || (layout == MemoryLayout::Auto && prefers_channels_last(net.spec()));
  if (!nhwc_layout) return net.forward(lr_color, info);
  const auto nhwc = [](const torch::Tensor& t) {
    return t.defined() ? t.contiguous(torch::MemoryFormat::ChannelsLast) : t;
  };
  return net.forward(nhwc(lr_color), nhwc(info)).contiguous();
}

}  // namespace cgsr
