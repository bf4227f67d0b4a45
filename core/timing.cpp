#include "core/timing.h"

#include <algorithm>
#include <chrono>

#include "core/error.h"

namespace cgsr {

double median(std::vector<double> values) {
  if (values.empty()) throw Error("median", "no values", ErrorKind::Internal);
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

LatencyStats measure_latency(const std::function<void()>& run, int warmup, int runs) {
  for (int i = 0; i < warmup; ++i) run();
  std::vector<double> ms;
  for (int i = 0; i < std::max(1, runs); ++i) {
    const auto start = std::chrono::steady_clock::now();
    run();
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  }
  LatencyStats s;
  s.median_ms = median(ms);
  s.min_ms = *std::min_element(ms.begin(), ms.end());
  s.max_ms = *std::max_element(ms.begin(), ms.end());
  s.runs = static_cast<int>(ms.size());
  return s;
}

}  // namespace cgsr
