#pragma once
// Activation memory layout inside training and inference. Interfaces stay NCHW (docs/design.md);
// inside, a network runs in the layout measured fastest for it on this machine. With Debian's
// LibTorch (reference BLAS, oneDNN convolutions) channels-last is usually 2-4x faster, but the
// choice is measured, not assumed, and NCHW stays available.
//
//   set_parameter_layout(*net, MemoryLayout::Nhwc);   // 4-D weights in place; same tensors
//   auto y = net->forward(to_layout(x, MemoryLayout::Nhwc));
//   MemoryLayout best = measured_layout("pan x2 train 4x3x24x24", [&](MemoryLayout l) { step(l); });

#include <torch/nn/module.h>
#include <torch/types.h>

#include <functional>
#include <string>

#include "core/enum_names.h"

namespace cgsr {

enum class MemoryLayout {
  Auto,  // measured per network and input size (measured_layout)
  Nchw,  // contiguous
  Nhwc,  // channels-last
};
template <>
struct EnumNames<MemoryLayout> {
  static constexpr const char* kind = "memory layout";
  static const std::vector<std::string>& names();  // auto, nchw, nhwc
};

// A 4-D tensor in `layout` (a no-op when it already is); other tensors and Auto pass through.
torch::Tensor to_layout(const torch::Tensor& t, MemoryLayout layout);

// Re-lays every 4-D parameter and buffer of `module` in place (set_data): the tensors keep their
// identity, so optimizers and graphs holding them stay valid.
void set_parameter_layout(torch::nn::Module& module, MemoryLayout layout);

// Times run(Nchw) and run(Nhwc) in interleaved rounds (after one warm-up each) and returns the
// faster; the answer is remembered under `key` for the rest of the process, so each network
// and input size is measured once per run. `run` must leave no state behind.
MemoryLayout measured_layout(const std::string& key, const std::function<void(MemoryLayout)>& run, int rounds = 3);

}  // namespace cgsr
