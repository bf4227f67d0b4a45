// Frame time of the classic upscalers (eval/baselines) at 1080p output: one random frame
// [1, 3, 540, 960] in [0,1] upscaled x2 to 1920x1080 on 2 threads (LibTorch intra-op and TBB).
// Each benchmark runs 9 repetitions; the median line is the one to quote (ms per frame).
//
//   build/bench/bench_baselines [--benchmark_filter=fsr]

#include <benchmark/benchmark.h>
#include <torch/torch.h>

#include "core/runtime.h"
#include "eval/baselines/fsr1.h"
#include "eval/baselines/interpolation.h"

namespace {

using namespace cgsr;

const torch::Tensor& frame() {
  static const torch::Tensor lr = [] {
    torch::manual_seed(1);
    return torch::rand({1, 3, 540, 960});
  }();
  return lr;
}

template <class Upscale>
void BM_Upscale(benchmark::State& state, Upscale upscale) {
  set_threads(2);
  const torch::Tensor& lr = frame();
  for (auto _ : state) {
    torch::Tensor sr = upscale(lr, 2);
    benchmark::DoNotOptimize(sr.data_ptr());
  }
  state.SetItemsProcessed(state.iterations());
  state.SetLabel("960x540 -> 1920x1080, 2 threads");
}

void per_frame(benchmark::internal::Benchmark* b) {
  b->Unit(benchmark::kMillisecond)->UseRealTime()->Repetitions(9)->ReportAggregatesOnly(true);
}

BENCHMARK_CAPTURE(BM_Upscale, nearest, upscale_nearest)->Apply(per_frame);
BENCHMARK_CAPTURE(BM_Upscale, bilinear, upscale_bilinear)->Apply(per_frame);
BENCHMARK_CAPTURE(BM_Upscale, bicubic, upscale_bicubic)->Apply(per_frame);
BENCHMARK_CAPTURE(BM_Upscale, lanczos, [](const torch::Tensor& x, int s) { return upscale_lanczos(x, s); })
    ->Apply(per_frame);
BENCHMARK_CAPTURE(BM_Upscale, fsr, [](const torch::Tensor& x, int s) { return upscale_fsr1(x, s); })->Apply(per_frame);

}  // namespace

BENCHMARK_MAIN();
