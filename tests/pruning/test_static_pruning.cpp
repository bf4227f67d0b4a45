// Static pruning keeps the widest selected pattern and nothing else: the smaller network computes
// what that pattern computed, every other selected pattern runs the same on it, and unused
// rendering channels and the geometry head are left out.
#include <gtest/gtest.h>

#include "core/error.h"
#include "pruning/pattern_networks.h"
#include "pruning/static_pruning.h"
#include "tests/pruning/pruning_cases.h"

using namespace cgsr;
using namespace cgsr::test;

namespace {
torch::Tensor pick(const torch::Tensor& info, const std::vector<int64_t>& rows) {
  return info.index_select(1, torch::tensor(rows, torch::kLong));
}
}  // namespace

TEST(StaticPruning, TheStaticNetworkIsTheWidestSelectedPattern) {
  torch::manual_seed(8);
  for (const auto& c : net_cases()) {
    SCOPED_TRACE(c.name);
    SRNetwork net(c.spec);
    randomize(*net);
    net->eval();
    const PatternPool pool = nested_pool(find_units(net->describe(false)), {1.0, 0.7, 0.4});
    StaticPruneOptions options;
    options.rit_threshold = 0;
    const auto [color, info] = inputs_for(*net, 6, 5);
    PatternNetworks full(*net, pool);
    torch::NoGradGuard no_grad;

    // Every pattern selected: the static network is the network (the union is the widest).
    StaticPruning all = static_prune(*net, pool, {2, 1, 1}, options);
    EXPECT_EQ(all.kept, (std::vector<int>{0, 1, 2}));
    EXPECT_EQ(all.network->spec().widths, net->spec().widths);
    EXPECT_LT(max_diff(all.network->forward(color, info), net->forward(color, info)), 1e-5);

    // The widest never selected: it goes, and the next one is the static network.
    StaticPruning pruned = static_prune(*net, pool, {0, 3, 2}, options);
    EXPECT_EQ(pruned.kept, (std::vector<int>{1, 2}));
    for (const auto& u : pool.units)
      for (const auto& g : u.groups) {
        EXPECT_EQ(pruned.network->spec().group_width(g), pool.widths[1].at(g));
        EXPECT_EQ(pruned.channels.at(g).size(), static_cast<size_t>(pool.widths[1].at(g)));
      }
    EXPECT_LT(max_diff(pruned.network->forward(color, info), full.run(1, color, info)), 1e-4);
    PatternNetworks small(*pruned.network, pruned.pool);
    ASSERT_EQ(small.size(), 2);
    EXPECT_LT(max_diff(small.run(1, color, info), full.run(2, color, info)), 1e-4);
    EXPECT_EQ(pruned.left_out["patterns"]["kept"].get<std::vector<int>>(), (std::vector<int>{1, 2}));

    EXPECT_THROW(static_prune(*net, pool, {0, 0, 0}, options), Error);
  }
}

TEST(StaticPruning, LeavesOutUnusedRenderingChannelsAndTheGeometryHead) {
  torch::manual_seed(9);
  ArchSpec spec = small_spec("pan", 2, 1, 4, 6, /*rit=*/true);
  spec.geometry.enabled = true;
  spec = resolve_spec(spec);
  SRNetwork net(spec);
  randomize(*net);
  net->eval();
  // The spec's channels in fixed order: depth, normal_angle, edge -> gate positions 0, 1, 2.
  {
    torch::NoGradGuard no_grad;
    net->rit_gate().fill_(1.0f);
    net->rit_gate()[1] = 0.0f;
  }
  const PatternPool pool = nested_pool(find_units(net->describe(false)), {1.0, 0.5});
  StaticPruning pruned = static_prune(*net, pool, {1, 1}, StaticPruneOptions{});
  EXPECT_EQ(pruned.rit_channels_dropped, (std::vector<std::string>{"normal_angle"}));
  EXPECT_EQ(pruned.network->spec().rit.channels, (std::vector<std::string>{"depth", "edge"}));
  EXPECT_FALSE(pruned.network->has_geometry_head());
  EXPECT_TRUE(pruned.left_out["geometry_head"].get<bool>());
  EXPECT_EQ(pruned.left_out["rit_channels"][0]["channel"], "normal_angle");
  const auto [color, info] = inputs_for(*net, 5, 5);
  torch::NoGradGuard no_grad;
  EXPECT_LT(max_diff(pruned.network->forward(color, pick(info, {0, 2})), net->forward(color, info)), 1e-5);
}
