// Static pruning removes exactly what no frame selects, and nothing else: the smaller network
// computes the masked union, and each kept pattern runs the same on the smaller network.
#include <gtest/gtest.h>

#include "pruning/pattern_executor.h"
#include "pruning/static_pruning.h"
#include "tests/pruning/pruning_cases.h"

using namespace cgsr;
using namespace cgsr::test;

namespace {
// Unit u never selects pattern (u % 3); the others are selected.
std::vector<std::vector<int64_t>> counts_skipping_one(const PatternPool& pool) {
  std::vector<std::vector<int64_t>> counts;
  for (size_t u = 0; u < pool.units.size(); ++u) {
    std::vector<int64_t> c(pool.units[u].patterns.size(), 2);
    c[u % c.size()] = 0;
    counts.push_back(c);
  }
  return counts;
}

torch::Tensor pick(const torch::Tensor& info, const std::vector<int64_t>& rows) {
  return info.index_select(1, torch::tensor(rows, torch::kLong));
}
}  // namespace

TEST(StaticPruning, RemovesExactlyTheNeverSelectedChannels) {
  torch::manual_seed(8);
  for (const auto& c : net_cases()) {
    SCOPED_TRACE(c.name);
    SRNetwork net(c.spec);
    randomize(*net);
    net->eval();
    const auto units = find_units(net->describe(false));
    const PatternPool pool = random_pool(units, 3, 0.4, 21);
    const auto counts = counts_skipping_one(pool);
    StaticPruneOptions options;
    options.rit_threshold = 0;
    StaticPruning pruned = static_prune(*net, pool, counts, options);

    // Widths are the unions of the selected patterns; the removed lists are their complements.
    PatternPool selected;
    for (size_t u = 0; u < pool.units.size(); ++u) {
      UnitPatterns s{pool.units[u].unit, {}};
      for (size_t k = 0; k < pool.units[u].patterns.size(); ++k)
        if (counts[u][k] > 0) s.patterns.push_back(pool.units[u].patterns[k]);
      selected.units.push_back(s);
      EXPECT_EQ(pruned.kept[u].size(), 2u);
    }
    const auto expected = selected.union_selection();
    EXPECT_EQ(pruned.channels, expected);
    for (const auto& [group, kept] : expected) {
      EXPECT_EQ(pruned.network->spec().group_width(group), static_cast<int>(kept.size()));
      const auto removed = pruned.left_out["channels"][group]["removed"].get<std::vector<int64_t>>();
      EXPECT_EQ(removed.size() + kept.size(), static_cast<size_t>(net->spec().group_width(group)));
      for (int64_t r : removed) EXPECT_FALSE(std::binary_search(kept.begin(), kept.end(), r));
    }
    // Everything else is untouched.
    for (const auto& [group, width] : net->spec().widths.entries())
      if (!expected.count(group)) {
        EXPECT_EQ(pruned.network->spec().widths.at(group), width);
      }

    // The smaller network is the dense network restricted to the union...
    const auto [color, info] = inputs_for(*net, 6, 5);
    torch::NoGradGuard no_grad;
    EXPECT_LT(max_diff(pruned.network->forward(color, info), masked_dense(*net, expected, color, info)), 1e-5);
    // ...and each kept pattern computes on it what it computed on the full network.
    PatternExecutor big(*net, pool), small(*pruned.network, pruned.pool);
    for (int j = 0; j < 2; ++j) {
      std::vector<int> old_choice, new_choice;
      for (size_t u = 0; u < pool.units.size(); ++u) {
        old_choice.push_back(pruned.kept[u][j]);
        new_choice.push_back(j);
      }
      EXPECT_LT(max_diff(small.run(color, info, new_choice), big.run(color, info, old_choice)), 1e-5);
    }
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
  const auto units = find_units(net->describe(false));
  const PatternPool pool = random_pool(units, 2, 1.0, 1);  // keep everything
  std::vector<std::vector<int64_t>> counts;
  for (const auto& u : pool.units) counts.push_back(std::vector<int64_t>(u.patterns.size(), 1));
  StaticPruning pruned = static_prune(*net, pool, counts, StaticPruneOptions{});
  EXPECT_EQ(pruned.rit_channels_dropped, (std::vector<std::string>{"normal_angle"}));
  EXPECT_EQ(pruned.network->spec().rit.channels, (std::vector<std::string>{"depth", "edge"}));
  EXPECT_FALSE(pruned.network->has_geometry_head());
  EXPECT_TRUE(pruned.left_out["geometry_head"].get<bool>());
  EXPECT_EQ(pruned.left_out["rit_channels"][0]["channel"], "normal_angle");
  const auto [color, info] = inputs_for(*net, 5, 5);
  torch::NoGradGuard no_grad;
  EXPECT_LT(max_diff(pruned.network->forward(color, pick(info, {0, 2})), net->forward(color, info)), 1e-5);
}
