#include <gtest/gtest.h>

#include <numeric>
#include <vector>

#include "core/error.h"
#include "core/timing.h"

using namespace cgsr;

// Every field is filled, for cgsr's own timings and ONNX Runtime's alike (the report's JSON
// once carried a mean of 0 for ONNX Runtime, which filled in the median alone).
TEST(Timing, SummaryFillsEveryStatistic) {
  const LatencyStats s = summarize_latency({5, 1, 3, 2, 4});
  EXPECT_DOUBLE_EQ(s.median_ms, 3);
  EXPECT_DOUBLE_EQ(s.min_ms, 1);
  EXPECT_DOUBLE_EQ(s.max_ms, 5);
  EXPECT_DOUBLE_EQ(s.mean_ms, 3);
  EXPECT_DOUBLE_EQ(s.p95_ms, 5);
  EXPECT_EQ(s.runs, 5);

  std::vector<double> twenty(20);
  std::iota(twenty.begin(), twenty.end(), 1.0);
  EXPECT_DOUBLE_EQ(summarize_latency(twenty).p95_ms, 19);  // nearest rank: ceil(0.95 * 20)
  EXPECT_DOUBLE_EQ(summarize_latency(twenty).median_ms, 10.5);
  EXPECT_THROW(summarize_latency({}), Error);
}
