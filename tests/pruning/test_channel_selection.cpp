// Channel selections narrow layouts position by position (pixel-shuffle repeats included) and
// gather consistent weights; bad selections are errors naming the group.
#include <gtest/gtest.h>

#include "core/error.h"
#include "models/channel_selection.h"
#include "tests/pruning/pruning_cases.h"

using namespace cgsr;
using namespace cgsr::test;

TEST(ChannelSelection, PositionsFollowSegmentsAndRepeats) {
  const graph::Layout layout = {{"a", 3, 1, true}, {"rgb", 2, 1, false}, {"up1", 3, 4, true}};
  const ChannelSelection keep = {{"a", {0, 2}}, {"up1", {1}}};
  EXPECT_EQ(selected_positions(layout, keep), (std::vector<int64_t>{0, 2, 3, 4, 9, 10, 11, 12}));
  const auto narrowed = selected_layout(layout, keep);
  EXPECT_EQ(narrowed[0].channels, 2);
  EXPECT_EQ(narrowed[1].channels, 2);
  EXPECT_EQ(narrowed[2].channels, 1);
  EXPECT_EQ(narrowed[2].repeat, 4);
}

TEST(ChannelSelection, SelectingEveryChannelIsTheSameNetwork) {
  torch::manual_seed(4);
  SRNetwork net(small_spec("edsr", 4, 1, 5, 6));
  randomize(*net);
  const auto g = net->describe(false);
  ChannelSelection all;
  for (const auto& [group, width] : group_widths(g)) {
    std::vector<int64_t> c(width);
    for (int64_t i = 0; i < width; ++i) c[i] = i;
    all[group] = c;
  }
  const auto [color, info] = inputs_for(*net, 5, 4);
  torch::NoGradGuard no_grad;
  EXPECT_TRUE(torch::equal(graph::run(select_channels(g, all), {{"color", color}}).front().second,
                           net->forward(color)));
}

TEST(ChannelSelection, ResidualStreamNarrowsConsistently) {
  // Narrowing the residual stream (not a per-frame unit, but a valid structured selection) keeps
  // every addition consistent and equals the masked computation with the stream's channels zeroed.
  torch::manual_seed(5);
  SRNetwork net(small_spec("pan", 2, 2, 4, 6));
  randomize(*net);
  const auto g = net->describe(false);
  const ChannelSelection keep = {{"features", {0, 2, 3, 5}}, {"block1_att", {0, 3}}};
  const auto [color, info] = inputs_for(*net, 6, 5);
  torch::NoGradGuard no_grad;
  const auto small = graph::run(select_channels(g, keep), {{"color", color}}).front().second;
  EXPECT_LT(max_diff(small, masked_dense(*net, keep, color, info)), 1e-5);
}

TEST(ChannelSelection, BadSelectionsAreErrors) {
  SRNetwork net(small_spec("pan", 2, 1, 4, 6));
  const auto g = net->describe(false);
  EXPECT_THROW(select_channels(g, {{"nope", {0}}}), Error);
  EXPECT_THROW(select_channels(g, {{"block0_a", {}}}), Error);
  EXPECT_THROW(select_channels(g, {{"block0_a", {2, 1}}}), Error);
  EXPECT_THROW(select_channels(g, {{"block0_a", {0, 4}}}), Error);
}
