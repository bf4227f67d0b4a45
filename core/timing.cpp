#include "core/timing.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/error.h"

namespace cgsr {

double median(std::vector<double> values) {
  if (values.empty()) throw Error("median", "no values", ErrorKind::Internal);
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

LatencyStats summarize_latency(const std::vector<double>& ms) {
  LatencyStats s;
  s.median_ms = median(ms);
  s.min_ms = *std::min_element(ms.begin(), ms.end());
  s.max_ms = *std::max_element(ms.begin(), ms.end());
  double sum = 0;
  for (double v : ms) sum += v;
  s.mean_ms = sum / static_cast<double>(ms.size());
  std::vector<double> sorted = ms;
  std::sort(sorted.begin(), sorted.end());
  const size_t rank = static_cast<size_t>(std::ceil(0.95 * static_cast<double>(sorted.size())));
  s.p95_ms = sorted[std::max<size_t>(rank, 1) - 1];
  s.runs = static_cast<int>(ms.size());
  return s;
}

namespace {

double time_ms(const std::function<void()>& run) {
  const auto start = std::chrono::steady_clock::now();
  run();
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}
}  // namespace

LatencyStats measure_latency(const std::function<void()>& run, int warmup, int runs) {
  return measure_latency_interleaved({run}, warmup, runs).front();
}

std::vector<LatencyStats> measure_latency_interleaved(const std::vector<std::function<void()>>& runs, int warmup,
                                                      int rounds) {
  for (const auto& run : runs)
    for (int i = 0; i < warmup; ++i) run();
  std::vector<std::vector<double>> ms(runs.size());
  for (int r = 0; r < std::max(1, rounds); ++r)
    for (size_t t = 0; t < runs.size(); ++t) ms[t].push_back(time_ms(runs[t]));
  std::vector<LatencyStats> out;
  for (const auto& m : ms) out.push_back(summarize_latency(m));
  return out;
}

}  // namespace cgsr
