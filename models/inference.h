#pragma once
// Running a trained network for inference: eval mode, no autograd, and the memory layout
// measured fastest for the network on this machine (memory_layout.h). Threads are the
// process-wide setting (core/runtime.h set_threads, i.e. --threads).

#include <torch/types.h>

#include <string>

#include "models/memory_layout.h"
#include "models/sr_network.h"

namespace cgsr {

// The layout infer() runs `net` in for inputs shaped like these: Nchw or Nhwc as requested; for
// Auto, measured once per network and batch on a crop of at most 160x120 LR pixels (timing the
// full size would cost more than it saves on 1080p frames) and remembered for the process.
MemoryLayout inference_layout(SRNetworkImpl& net, const torch::Tensor& lr_color, const torch::Tensor& info,
                              MemoryLayout requested = MemoryLayout::Auto);

// Which implementation runs a trained network's inference.
enum class InferenceEngine {
  Fused,     // FusedGraph (fused_graph.h): oneDNN with element-wise ops fused into convolutions
  LibTorch,  // the modules' forward in the measured layout: the reference the tests compare with
};
template <>
struct EnumNames<InferenceEngine> {
  static constexpr const char* kind = "inference engine";
  static const std::vector<std::string>& names();  // fused, libtorch
};

// [N, 3, s*h, s*w], contiguous NCHW. Puts the network in eval mode.
torch::Tensor infer(SRNetworkImpl& net, const torch::Tensor& lr_color, const torch::Tensor& info = {},
                    MemoryLayout layout = MemoryLayout::Auto);

}  // namespace cgsr
