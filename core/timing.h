#pragma once
// Wall-clock measurement for benchmarks and latency columns: warm-up runs, then repeated runs
// summarized by their median (robust on a shared, noisy machine) with min and max.

#include <functional>
#include <vector>

namespace cgsr {

struct LatencyStats {
  double median_ms = 0, min_ms = 0, max_ms = 0;
  double mean_ms = 0, p95_ms = 0;  // p95: the nearest-rank 95th percentile
  int runs = 0;
};

// Median, min, max, mean and p95 of measured times (ms); an Error when there are none.
LatencyStats summarize_latency(const std::vector<double>& ms);

LatencyStats measure_latency(const std::function<void()>& run, int warmup = 2, int runs = 10);

// Several targets timed in interleaved rounds (one run of each per round, after `warmup` runs
// of each), so that load changing on a shared machine hits all of them alike and their ratios
// hold. One LatencyStats per target, in order.
std::vector<LatencyStats> measure_latency_interleaved(const std::vector<std::function<void()>>& runs, int warmup = 2,
                                                      int rounds = 10);

// Median of a sample (the mean of the two middle values for an even count).
double median(std::vector<double> values);

}  // namespace cgsr
