// The controls of equal latency: magnitude pruning narrows the pruning units alone, uniform width
// every group; both keep the channels of largest magnitude, and the rate is found for a latency.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "models/complexity.h"
#include "models/importance/channel_importance.h"
#include "pruning/equal_latency_controls.h"
#include "pruning/prunable_units.h"
#include "tests/pruning/pruning_cases.h"

using namespace cgsr;
using namespace cgsr::test;

TEST(EqualLatencyControls, MagnitudeNarrowsTheUnitsUniformEveryGroup) {
  SRNetwork net(small_spec("pan", 2, 2, 8, 8, /*rit=*/true));
  const auto mmp = control_subnet(*net, ControlKind::Magnitude, 0.5);
  const auto uniform = control_subnet(*net, ControlKind::Uniform, 0.5);
  EXPECT_EQ(mmp.widths.at("features"), 8);  // the residual stream stays whole
  EXPECT_EQ(mmp.widths.at("block0_a"), 4);
  EXPECT_EQ(uniform.widths.at("features"), 4);
  EXPECT_EQ(uniform.widths.at("rit"), 3);  // round(0.5 x 5)
  EXPECT_EQ(mmp.blocks.size(), 2u);
  EXPECT_THROW(control_subnet(*net, ControlKind::Uniform, 0), Error);
  EXPECT_EQ(control_label(ControlKind::Magnitude), "MMP");
}

TEST(EqualLatencyControls, KeepTheLargestChannelsAndMatchACost) {
  torch::manual_seed(31);
  SRNetwork net(small_spec("pan", 2, 2, 8, 8, /*rit=*/true));
  randomize(*net);
  net->eval();
  // MACs stand in for latency: the matching is exercised without timing this machine.
  const NetworkCost macs = [](const SRNetwork& n) {
    return static_cast<double>(complexity(n->describe(false), 32, 24).macs);
  };
  const ControlNetwork half = control_at_rate(*net, ControlKind::Magnitude, 0.5, macs);
  // Its first block's `a` group holds the 4 channels of largest L1 magnitude, largest first.
  const auto full = channel_importance(*net).at("block0_a").detach();
  const auto kept = channel_importance(*half.network).at("block0_a").detach();
  const auto top = std::get<0>(full.sort(0, /*descending=*/true)).slice(0, 0, 4);
  EXPECT_TRUE(torch::allclose(kept, top, 1e-5, 1e-6));
  EXPECT_EQ(half.cost, macs(half.network));
  // The uniform control at MMP's cost: within it, and one bisection step wider is over it.
  const ControlNetwork matched = control_at_latency(*net, ControlKind::Uniform, half.cost, macs);
  EXPECT_LE(matched.cost, half.cost);
  EXPECT_GT(matched.rate, 0.05);
  EXPECT_LT(matched.rate, 1.0);
  EXPECT_GT(control_at_rate(*net, ControlKind::Uniform, matched.rate + 0.95 / 64, macs).cost, half.cost);
  // A target below the narrowest control returns the narrowest; one above the network, the network.
  EXPECT_DOUBLE_EQ(control_at_latency(*net, ControlKind::Uniform, 0, macs).rate, 0.05);
  EXPECT_DOUBLE_EQ(control_at_latency(*net, ControlKind::Uniform, 1e18, macs).rate, 1.0);
}
