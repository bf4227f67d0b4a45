#pragma once
// Wall-clock measurement for benchmarks and latency columns: warm-up runs, then repeated runs
// summarized by their median (robust on a shared, noisy machine) with min and max.

#include <functional>
#include <vector>

namespace cgsr {

struct LatencyStats {
  double median_ms = 0, min_ms = 0, max_ms = 0;
  int runs = 0;
};

LatencyStats measure_latency(const std::function<void()>& run, int warmup = 2, int runs = 10);

// Median of a sample (the mean of the two middle values for an even count).
double median(std::vector<double> values);

}  // namespace cgsr
