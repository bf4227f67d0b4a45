// Frame time of the quality metrics at 1080p, what `cgsr eval` adds per frame on top of the
// upscaling: PSNR, SSIM, and the edge metric (edge_psnr: dilate_edges + masked_psnr) on a random output
// and reference [1, 3, 1080, 1920] with a sparse random edge map, on 2 threads. Each benchmark
// runs 9 repetitions; the median line is the one to quote (ms per frame).
//
//   build/bench/bench_metrics [--benchmark_filter=edge]

#include <benchmark/benchmark.h>
#include <torch/torch.h>

#include "core/metrics.h"
#include "core/runtime.h"
#include "render_data/edges.h"

namespace {

using namespace cgsr;

struct Images {
  torch::Tensor output, reference, edges, dilated;
};

const Images& images() {
  static const Images im = [] {
    torch::manual_seed(1);
    Images i;
    i.reference = torch::rand({1, 3, 1080, 1920});
    i.output = (i.reference + 0.05 * torch::randn_like(i.reference)).clamp(0, 1);
    i.edges = (torch::rand({1, 1080, 1920}) < 0.01).to(torch::kUInt8);  // ~1% edge pixels before dilation
    i.dilated = dilate_edges(i.edges);
    return i;
  }();
  return im;
}

template <class Metric>
void BM_Metric(benchmark::State& state, Metric metric) {
  set_threads(2);
  const Images& im = images();
  for (auto _ : state) benchmark::DoNotOptimize(metric(im));
  state.SetLabel("1920x1080, 2 threads");
}

void per_frame(benchmark::internal::Benchmark* b) {
  b->Unit(benchmark::kMillisecond)->UseRealTime()->Repetitions(9)->ReportAggregatesOnly(true);
}

BENCHMARK_CAPTURE(BM_Metric, psnr, [](const Images& i) { return psnr(i.output, i.reference).item<double>(); })
    ->Apply(per_frame);
BENCHMARK_CAPTURE(BM_Metric, ssim, [](const Images& i) { return ssim(i.output, i.reference).item<double>(); })
    ->Apply(per_frame);
BENCHMARK_CAPTURE(BM_Metric, dilate_edges, [](const Images& i) { return dilate_edges(i.edges).data_ptr(); })
    ->Apply(per_frame);
BENCHMARK_CAPTURE(BM_Metric, masked_psnr, [](const Images& i) {
  return masked_psnr(i.output, i.reference, i.dilated).at(0).inside_fraction;
})->Apply(per_frame);
BENCHMARK_CAPTURE(BM_Metric, edge_psnr, [](const Images& i) {
  return masked_psnr(i.output, i.reference, dilate_edges(i.edges)).at(0).inside_fraction;
})->Apply(per_frame);

}  // namespace

BENCHMARK_MAIN();
