#pragma once
// Running a trained network for inference: eval mode, no autograd, and the memory layout that
// measured fastest for the backbone on this machine. Threads are the process-wide setting
// (core/runtime.h set_threads, i.e. --threads).

#include <torch/types.h>

#include <string>

#include "models/sr_network.h"

namespace cgsr {

enum class MemoryLayout {
  Auto,  // the layout measured fastest for the spec (prefers_channels_last)
  Nchw,  // contiguous
  Nhwc,  // channels-last activations
};
MemoryLayout memory_layout_from_name(const std::string& name);  // auto | nchw | nhwc
const char* memory_layout_name(MemoryLayout layout);

// Channels-last (NHWC) activations only where measured faster (see inference.cpp).
bool prefers_channels_last(const ArchSpec& spec);

// [N, 3, s*h, s*w], contiguous NCHW. Puts the network in eval mode.
torch::Tensor infer(SRNetworkImpl& net, const torch::Tensor& lr_color, const torch::Tensor& info = {},
                    MemoryLayout layout = MemoryLayout::Auto);

}  // namespace cgsr
