#pragma once
// Activation memory layout inside training and inference. Interfaces stay NCHW (docs/design.md);
// inside, a network runs in the layout measured fastest for it on this machine. With Debian's
// LibTorch (reference BLAS, oneDNN convolutions) channels-last is usually 2-4x faster, but the
// choice is measured, not assumed, and NCHW stays available. `auto` is measured once per machine
// and remembered (measured_layout); `nchw` or `nhwc` in a config pins it.
//
//   set_parameter_layout(*net, MemoryLayout::Nhwc);   // 4-D weights in place; same tensors
//   auto y = net->forward(to_layout(x, MemoryLayout::Nhwc));
//   MemoryLayout best = measured_layout("pan x2 train 4x3x24x24", [&](MemoryLayout l) { step(l); });

#include <torch/nn/module.h>
#include <torch/types.h>

#include <filesystem>
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
// faster. A timing on a busy machine can flip the choice, and the layouts sum in different
// orders, so the choice is made once and then looked up, first found first:
//   1. this process's earlier answer for `key`;
//   2. the run directory's record (layout_record_scope: DIR/layouts.json, key -> layout), so a
//      rerun of a run directory (--resume, cgsr run rerunning a stage, another machine) runs in
//      the layout the run used;
//   3. this machine's cache (user_cache_dir()/layouts.json, keyed by `key`, the thread count and
//      the CPU model), so two runs of one config on one machine agree bit for bit whatever the
//      load; the cache is locked while a process reads, measures and writes it;
//   4. measured, then written to the cache and the record (atomically).
// `key` names the network and input shape; `run` must leave no state behind.
MemoryLayout measured_layout(const std::string& key, const std::function<void(MemoryLayout)>& run, int rounds = 3);

// While alive, measured_layout records its answers in `file` and takes them from there first
// (a command's run directory: cli/command.h, the pipeline's root). Nests; the innermost wins.
class LayoutRecordScope {
 public:
  explicit LayoutRecordScope(std::filesystem::path file);
  ~LayoutRecordScope();
  LayoutRecordScope(const LayoutRecordScope&) = delete;
  LayoutRecordScope& operator=(const LayoutRecordScope&) = delete;

 private:
  std::filesystem::path outer_;
};

// The machine cache's file (empty when there is no cache directory) and its key for `key`.
std::filesystem::path layout_cache_file();
std::string machine_layout_key(const std::string& key);

// Forgets this process's answers (step 1), as a new process would: for tests.
void forget_measured_layouts();

}  // namespace cgsr
