#include "models/memory_layout.h"

#include <spdlog/spdlog.h>
#include <torch/torch.h>

#include <map>
#include <mutex>

#include "core/error.h"
#include "core/timing.h"

namespace cgsr {

const std::vector<std::string>& EnumNames<MemoryLayout>::names() {
  static const std::vector<std::string> names = {"auto", "nchw", "nhwc"};
  return names;
}

torch::Tensor to_layout(const torch::Tensor& t, MemoryLayout layout) {
  if (!t.defined() || t.dim() != 4 || layout == MemoryLayout::Auto) return t;
  return t.contiguous(layout == MemoryLayout::Nhwc ? torch::MemoryFormat::ChannelsLast
                                                   : torch::MemoryFormat::Contiguous);
}

void set_parameter_layout(torch::nn::Module& module, MemoryLayout layout) {
  if (layout == MemoryLayout::Auto) return;
  torch::NoGradGuard no_grad;
  const auto relay = [&](torch::Tensor& t) {
    if (t.defined() && t.dim() == 4) {
      const auto laid = to_layout(t, layout);
      if (!laid.is_same(t)) t.set_data(laid);
    }
  };
  for (auto& p : module.parameters()) {
    relay(p);
    if (p.grad().defined() && p.grad().dim() == 4) p.mutable_grad() = to_layout(p.grad(), layout);
  }
  for (auto& b : module.buffers()) relay(b);
}

MemoryLayout measured_layout(const std::string& key, const std::function<void(MemoryLayout)>& run, int rounds) {
  static std::mutex mutex;
  static std::map<std::string, MemoryLayout> chosen;
  {
    std::lock_guard<std::mutex> lock(mutex);
    if (auto it = chosen.find(key); it != chosen.end()) return it->second;
  }
  const auto stats = measure_latency_interleaved({[&] { run(MemoryLayout::Nchw); }, [&] { run(MemoryLayout::Nhwc); }},
                                                 /*warmup=*/1, rounds);
  const MemoryLayout best = stats[1].median_ms < stats[0].median_ms ? MemoryLayout::Nhwc : MemoryLayout::Nchw;
  spdlog::info("layout for {}: {} (nchw {:.1f} ms, nhwc {:.1f} ms, median of {})", key, enum_name(best),
               stats[0].median_ms, stats[1].median_ms, rounds);
  std::lock_guard<std::mutex> lock(mutex);
  return chosen.emplace(key, best).first->second;
}

}  // namespace cgsr
