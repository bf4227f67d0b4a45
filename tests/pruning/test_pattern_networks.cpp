// Patterns as networks that run: each pattern on the fused path equals its subnet graph, and a
// pool reads the network's weights once.
#include <gtest/gtest.h>

#include "pruning/pattern_networks.h"
#include "tests/pruning/pruning_cases.h"

using namespace cgsr;
using namespace cgsr::test;

TEST(PatternNetworks, EachPatternEqualsItsSubnetGraph) {
  for (const auto& c : net_cases()) {
    SCOPED_TRACE(c.name);
    torch::manual_seed(11);
    SRNetwork net(c.spec);
    randomize(*net);
    net->eval();
    const PatternPool pool = random_pool(*net, 3, 5);
    PatternNetworks patterns(*net, pool);
    const auto [color, info] = inputs_for(*net, 9, 6);
    for (int k = 0; k < pool.size(); ++k) {
      EXPECT_LT(max_diff(patterns.run(k, color, info), run_pattern(*net, pool, k, color, info)), 1e-4) << k;
      EXPECT_EQ(patterns.cost(k, 9, 6).macs, complexity(subnet_graph(*net, pool.patterns[k]), 9, 6).macs);
    }
  }
}

TEST(PatternNetworks, SnapshotIgnoresLaterTraining) {
  torch::manual_seed(12);
  SRNetwork net(small_spec("pan", 2, 2, 6, 8));
  randomize(*net);
  net->eval();
  const PatternPool pool = random_pool(*net, 2, 3);
  PatternNetworks patterns(*net, pool);
  const auto [color, info] = inputs_for(*net, 8, 8);
  const auto before = patterns.run(0, color, info);
  randomize(*net);
  EXPECT_TRUE(torch::equal(patterns.run(0, color, info), before));
  PatternPool other = pool;
  other.spec = small_spec("pan", 2, 1, 6, 8);
  EXPECT_ANY_THROW(PatternNetworks(*net, other));
}
