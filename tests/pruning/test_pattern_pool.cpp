// The pool of nested patterns: widths from keep rates, channels ordered by importance (the
// reordered network computes the same), and the pool's file form with its checks.
#include <gtest/gtest.h>

#include "core/error.h"
#include "pruning/pattern_pool.h"
#include "tests/pruning/pruning_cases.h"

using namespace cgsr;
using namespace cgsr::test;

namespace {
PrunableUnit two_groups() {
  PrunableUnit u;
  u.name = "block0";
  u.groups = {"block0_a", "block0_b"};
  u.widths = {4, 10};
  return u;
}
}  // namespace

TEST(PatternPool, NestedWidthsFromKeepRates) {
  const PatternPool pool = nested_pool({two_groups()}, {1.0, 0.5, 0.2});
  ASSERT_EQ(pool.size(), 3);
  EXPECT_EQ(pool.widths[0].at("block0_a"), 4);
  EXPECT_EQ(pool.widths[1].at("block0_a"), 2);
  EXPECT_EQ(pool.widths[2].at("block0_a"), 1);
  EXPECT_EQ(pool.widths[1].at("block0_b"), 5);
  EXPECT_EQ(pool.widths[2].at("block0_b"), 2);
  EXPECT_EQ(pool.selection(1).at("block0_b"), (std::vector<int64_t>{0, 1, 2, 3, 4}));
  EXPECT_DOUBLE_EQ(pool.channel_fraction(0), 1.0);
  EXPECT_DOUBLE_EQ(pool.channel_fraction(1), 7.0 / 14.0);
  EXPECT_DOUBLE_EQ(pool.channel_fraction(2), 3.0 / 14.0);
  EXPECT_THROW(pool.selection(3), Error);
  EXPECT_THROW(nested_pool({two_groups()}, {0.5, 0.5}), Error);  // not decreasing
  EXPECT_THROW(nested_pool({two_groups()}, {1.0, 0.0}), Error);
  EXPECT_THROW(nested_pool({two_groups()}, {0.2, 0.19}), Error);  // the same channels twice
}

TEST(PatternPool, OrdersChannelsByNormalizedImportance) {
  PrunableUnit u;
  u.name = "block0";
  u.groups = {"block0_a"};
  u.widths = {3};
  // Frame 0 has ten times the scale of frame 1; normalized, channel 2 wins on average.
  const std::vector<FrameImportance> frames = {{{"block0_a", torch::tensor({10.0f, 9.0f, 8.0f})}},
                                               {{"block0_a", torch::tensor({0.0f, 0.2f, 0.8f})}}};
  EXPECT_EQ(importance_order({u}, frames).at("block0_a"), (std::vector<int64_t>{2, 1, 0}));
  EXPECT_THROW(importance_order({u}, {}), Error);
  EXPECT_THROW(importance_order({u}, {{{"other", torch::ones({3})}}}), Error);
}

TEST(PatternPool, ReorderedNetworkComputesTheSame) {
  torch::manual_seed(3);
  for (const auto& c : net_cases()) {
    SCOPED_TRACE(c.name);
    SRNetwork net(c.spec);
    randomize(*net);
    net->eval();
    const auto units = find_units(net->describe(false));
    const auto order = random_order(units, 5);
    SRNetwork ordered = order_channels(*net, order).network;
    ordered->eval();
    const auto [color, info] = inputs_for(*net, 7, 5);
    torch::NoGradGuard no_grad;
    EXPECT_LT(max_diff(ordered->forward(color, info), net->forward(color, info)), 1e-4);
    // The channels really moved: the first unit group's producing weights are permuted.
    const auto& g = units.front().groups.front();
    const auto before = channel_importance(*net).at(g), after = channel_importance(*ordered).at(g);
    EXPECT_TRUE(torch::allclose(after, before.index_select(0, torch::tensor(order.at(g), torch::kLong))));
  }
}

TEST(PatternPool, JsonRoundTripAndChecks) {
  const PatternPool pool = nested_pool({two_groups()}, {1.0, 0.5});
  const auto j = to_json(pool);
  const PatternPool back = pool_from_json(j, {two_groups()}, "pool.json");
  EXPECT_EQ(back.widths, pool.widths);
  auto wider = j;
  wider["patterns"][1]["block0_a"] = 4;
  wider["patterns"][0]["block0_a"] = 3;
  EXPECT_THROW(pool_from_json(wider, {two_groups()}, "pool.json"), Error);  // not nested
  auto zero = j;
  zero["patterns"][1]["block0_b"] = 0;
  EXPECT_THROW(pool_from_json(zero, {two_groups()}, "pool.json"), Error);
  PrunableUnit other = two_groups();
  other.widths = {4, 8};
  try {
    pool_from_json(j, {other}, "pool.json");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("pool.json"), std::string::npos);
  }
}

TEST(PatternPool, KeepingPatternsNarrowsToTheWidestKept) {
  const PatternPool pool = nested_pool({two_groups()}, {1.0, 0.5, 0.2});
  PrunableUnit narrowed = two_groups();
  narrowed.widths = {2, 5};
  const PatternPool kept = keep_patterns(pool, {1, 2}, {narrowed});
  ASSERT_EQ(kept.size(), 2);
  EXPECT_EQ(kept.widths[0], pool.widths[1]);
  EXPECT_EQ(kept.widths[1], pool.widths[2]);
  EXPECT_DOUBLE_EQ(kept.channel_fraction(0), 1.0);
  EXPECT_THROW(keep_patterns(pool, {2, 1}, {narrowed}), Error);
}
