// The latency table's calibration: a least-squares fit that never lets a coefficient go negative,
// since a few noisy timings can otherwise make a small subnet predicted slower than a large one.
#include <gtest/gtest.h>

#include "models/latency_table.h"

using namespace cgsr;

namespace {
double calibrated(const LatencyTable& t, const LatencySample& s) { return t.predict(s.conv_ms, s.elements); }
}  // namespace

TEST(LatencyCalibration, FitsExactlyWhenTheTimingsFollowTheModel) {
  LatencyTable t;
  std::vector<LatencySample> samples;
  for (const auto& [conv, elements] : std::vector<std::pair<double, double>>{{1, 2e6}, {2, 1e6}, {3, 5e6}, {4, 3e6}})
    samples.push_back({conv, elements, 0.5 * conv + 0.2e-6 * elements + 0.3});
  fit_calibration(t, samples);
  EXPECT_NEAR(t.scale, 0.5, 1e-9);
  EXPECT_NEAR(t.element_ns, 0.2, 1e-9);
  EXPECT_NEAR(t.offset_ms, 0.3, 1e-9);
}

TEST(LatencyCalibration, NoCoefficientGoesNegativeOnNoisyTimings) {
  // Four subnets whose timings an unconstrained fit explains with a negative weight per element
  // (measured latency falling as elements grow): -0.25 ns.
  const std::vector<LatencySample> samples = {{1.0, 1e6, 1.4}, {1.5, 4e6, 1.3}, {2.0, 2e6, 2.4}, {2.6, 6e6, 2.1}};
  LatencyTable t;
  fit_calibration(t, samples);
  EXPECT_GT(t.scale, 0);
  EXPECT_GE(t.element_ns, 0);
  EXPECT_GE(t.offset_ms, 0);
  // The best fit under those bounds: no other non-negative choice of the free coefficients
  // explains the timings better (checked on a grid around the fit).
  const auto error = [&](const LatencyTable& c) {
    double e = 0;
    for (const auto& s : samples) e += (calibrated(c, s) - s.measured_ms) * (calibrated(c, s) - s.measured_ms);
    return e;
  };
  const double fitted = error(t);
  for (double ds : {-0.05, 0.0, 0.05})
    for (double de : {0.0, 0.01})
      for (double doff : {-0.05, 0.0, 0.05}) {
        LatencyTable other = t;
        other.scale += ds;
        other.element_ns += de;
        other.offset_ms += doff;
        if (other.offset_ms < 0) continue;
        EXPECT_GE(error(other), fitted - 1e-12) << ds << " " << de << " " << doff;
      }
  // Predictions grow with the convolutions' time and never fall below zero.
  EXPECT_GT(calibrated(t, {0.0, 0.0, 0}), -1e-12);
  EXPECT_LT(calibrated(t, samples[0]), calibrated(t, samples[3]));
}

TEST(LatencyCalibration, WithoutConvolutionsTheSumStandsAsItIs) {
  LatencyTable t;
  fit_calibration(t, {{0, 1e6, 1.0}, {0, 2e6, 1.5}});
  EXPECT_EQ(t.scale, 1);
  EXPECT_EQ(t.element_ns, 0);
  EXPECT_EQ(t.offset_ms, 0);
}
