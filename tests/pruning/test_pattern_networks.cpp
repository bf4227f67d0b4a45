// Nested patterns as networks: each pattern's fast-path output equals the masked dense network
// (and the differentiable masks used in training), its weights are views of the widest ones, the
// widest pattern is the network itself, and narrower patterns cost less.
#include <gtest/gtest.h>

#include "pruning/pattern_masks.h"
#include "pruning/pattern_networks.h"
#include "tests/pruning/pruning_cases.h"

using namespace cgsr;
using namespace cgsr::test;

TEST(PatternNetworks, EachPatternEqualsTheMaskedDenseNetwork) {
  torch::manual_seed(5);
  for (const auto& c : net_cases()) {
    SCOPED_TRACE(c.name);
    SRNetwork net(c.spec);
    randomize(*net);
    net->eval();
    const PatternPool pool = nested_pool(find_units(net->describe(false)), {1.0, 0.6, 0.3});
    PatternNetworks patterns(*net, pool);
    PatternMasks masks(*net, pool);
    const auto [color, info] = inputs_for(*net, 9, 7);
    torch::NoGradGuard no_grad;
    EXPECT_LT(max_diff(patterns.run(0, color, info), net->forward(color, info)), 1e-4);
    for (int k = 0; k < pool.size(); ++k) {
      SCOPED_TRACE(k);
      const auto out = patterns.run(k, color, info);
      EXPECT_LT(max_diff(out, masked_dense(*net, pool.selection(k), color, info)), 1e-4);
      EXPECT_LT(max_diff(out, masks.forward(color, info, masks.group_masks(k, 1))), 1e-4);
      if (k > 0) {
        EXPECT_LT(patterns.cost(k, 9, 7).macs, patterns.cost(k - 1, 9, 7).macs);
      }
    }
  }
}

TEST(PatternNetworks, NarrowWeightsAreViewsOfTheWidest) {
  torch::manual_seed(6);
  // Without a RIT every unit group leads the axes it appears in (a RIT's channels follow the
  // features in a concatenation, and narrowing them there gathers).
  SRNetwork net(small_spec("pan", 4, 2, 6, 8));
  randomize(*net);
  const PatternPool pool = nested_pool(find_units(net->describe(false)), {1.0, 0.5});
  PatternNetworks patterns(*net, pool);
  const auto& widest = patterns.graph(0);
  const auto& narrow = patterns.graph(1);
  // A narrowed weight is a view when each of its axes is one layer group (the first channels
  // lead the axis); an axis over a concatenation (PAN's conv3 reads a_out and b_out) is gathered.
  int views = 0, single_group = 0;
  for (size_t i = 0; i < narrow.ops.size(); ++i) {
    const auto& op = narrow.ops[i];
    if (!op.weight.defined() || op.weight.sizes() == widest.ops[i].weight.sizes()) continue;
    const bool one_group = narrow.values[op.output].layout.size() == 1 &&
                           (op.inputs.empty() || narrow.values[op.inputs[0]].layout.size() == 1);
    single_group += one_group;
    if (op.weight.is_alias_of(widest.ops[i].weight)) {
      ++views;
    } else {
      EXPECT_FALSE(one_group) << op.name << " was copied";
    }
  }
  EXPECT_GT(single_group, 0);
  EXPECT_GE(views, single_group);
}

TEST(PatternNetworks, SnapshotIgnoresLaterTraining) {
  torch::manual_seed(7);
  SRNetwork net(small_spec("edsr", 2, 1, 6, 8));
  randomize(*net);
  net->eval();
  PatternNetworks patterns(*net, nested_pool(find_units(net->describe(false)), {1.0, 0.5}));
  const auto [color, info] = inputs_for(*net, 6, 6);
  const auto before = patterns.run(1, color, info);
  {
    torch::NoGradGuard no_grad;
    for (auto& p : net->parameters()) p.add_(1.0);
  }
  EXPECT_TRUE(torch::equal(patterns.run(1, color, info), before));
}
