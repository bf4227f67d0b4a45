// A chosen pattern runs as smaller dense convolutions and computes exactly what the dense
// network computes with the removed channels masked out; the training-time masks agree too.
#include <gtest/gtest.h>

#include "core/error.h"
#include "models/complexity.h"
#include "pruning/channel_selection.h"
#include "pruning/pattern_executor.h"
#include "pruning/pattern_masks.h"
#include "tests/pruning/pruning_cases.h"

using namespace cgsr;
using namespace cgsr::test;

TEST(PatternExecutor, ChosenPatternEqualsMaskedDenseComputation) {
  torch::manual_seed(1);
  for (const auto& c : net_cases()) {
    SCOPED_TRACE(c.name);
    SRNetwork net(c.spec);
    randomize(*net);
    net->eval();
    const auto units = find_units(net->describe(false));
    ASSERT_FALSE(units.empty());
    PatternExecutor exec(*net, random_pool(units, 3, 0.5, 11));
    const auto [color, info] = inputs_for(*net, 7, 5);
    for (int trial = 0; trial < 4; ++trial) {
      std::vector<int> choice;
      for (size_t u = 0; u < units.size(); ++u) choice.push_back(static_cast<int>((u + trial) % 3));
      const auto fast = exec.run(color, info, choice);
      const auto reference = masked_dense(*net, exec.pool().selection(choice), color, info);
      EXPECT_LT(max_diff(fast, reference), 1e-5);
    }
  }
}

TEST(PatternExecutor, ExecutesSmallerConvolutions) {
  torch::manual_seed(2);
  SRNetwork net(small_spec("pan", 2, 2, 8, 8));
  randomize(*net);
  const auto units = find_units(net->describe(false));
  PatternExecutor exec(*net, random_pool(units, 2, 0.5, 3));
  const std::vector<int> choice(units.size(), 1);
  const graph::Graph& g = exec.graph_for(choice);
  const auto* k1 = g.find_op("backbone.blocks.0.k1");
  ASSERT_NE(k1, nullptr);
  EXPECT_EQ(k1->weight.size(0), 4);
  EXPECT_EQ(k1->weight.size(1), 4);
  const auto dense = complexity(*net, 16, 16), pruned = exec.cost(choice, 16, 16);
  EXPECT_LT(pruned.macs, dense.macs);
  EXPECT_LT(pruned.params, dense.params);
  // The residual stream keeps its width.
  EXPECT_EQ(g.find_op("backbone.blocks.0.conv3")->weight.size(0), 8);
}

TEST(PatternExecutor, HardMasksEqualExecution) {
  torch::manual_seed(3);
  for (const auto& c : net_cases()) {
    SCOPED_TRACE(c.name);
    SRNetwork net(c.spec);
    randomize(*net);
    net->eval();
    const auto units = find_units(net->describe(false));
    const PatternPool pool = random_pool(units, 3, 0.4, 5);
    PatternExecutor exec(*net, pool);
    PatternMasks masks(*net, pool);
    const auto [color, info] = inputs_for(*net, 6, 6, 2);
    // Item 0 picks pattern 0 everywhere, item 1 pattern 2.
    std::vector<torch::Tensor> weights;
    for (size_t u = 0; u < units.size(); ++u) weights.push_back(torch::tensor({{1.f, 0.f, 0.f}, {0.f, 0.f, 1.f}}));
    torch::NoGradGuard no_grad;
    const auto masked = masks.forward(color, info, masks.group_masks(weights));
    for (int item : {0, 1}) {
      const std::vector<int> choice(units.size(), item == 0 ? 0 : 2);
      const auto one = [&](const torch::Tensor& t) { return t.defined() ? t.slice(0, item, item + 1) : t; };
      EXPECT_LT(max_diff(masked.slice(0, item, item + 1), exec.run(one(color), one(info), choice)), 1e-5);
    }
  }
}

TEST(PatternExecutor, RejectsBadChoices) {
  SRNetwork net(small_spec("edsr", 2, 1, 4, 4));
  const auto units = find_units(net->describe(false));
  PatternExecutor exec(*net, random_pool(units, 2, 0.5, 1));
  const auto [color, info] = inputs_for(*net, 4, 4);
  EXPECT_THROW(exec.run(color, info, {}), Error);
  EXPECT_THROW(exec.run(color, info, std::vector<int>(units.size(), 2)), Error);
}
