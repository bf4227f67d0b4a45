// Static pruning: the static network is the union of the chosen patterns, each of which computes
// in it exactly what it did before; the geometry head is left out.
#include <gtest/gtest.h>

#include "core/error.h"
#include "pruning/static_pruning.h"
#include "tests/pruning/pruning_cases.h"

using namespace cgsr;
using namespace cgsr::test;

TEST(StaticPruning, TheStaticNetworkIsTheUnionOfTheChosenPatterns) {
  for (const auto& c : net_cases()) {
    SCOPED_TRACE(c.name);
    torch::manual_seed(13);
    ArchSpec spec = c.spec;
    spec.geometry.enabled = spec.rit.enabled;
    SRNetwork net(resolve_spec(spec));
    randomize(*net);
    net->eval();
    const PatternPool pool = random_pool(*net, 4, 9);
    const StaticPruning pruned = static_prune(*net, pool, {3, 0, 2, 1});
    EXPECT_EQ(pruned.kept, (std::vector<int>{0, 2, 3}));
    EXPECT_EQ(pruned.pool.size(), 3);
    EXPECT_FALSE(pruned.network->has_geometry_head());
    EXPECT_EQ(pruned.left_out["patterns"], nlohmann::ordered_json::array({1}));
    const auto [color, info] = inputs_for(*net, 7, 6);
    for (int i = 0; i < pruned.pool.size(); ++i)
      EXPECT_LT(max_diff(run_pattern(*net, pool, pruned.kept[i], color, info),
                         run_pattern(*pruned.network, pruned.pool, i, color, info)),
                1e-5)
          << i;
    EXPECT_THROW(static_prune(*net, pool, {0, 0, 0, 0}), Error);
  }
}
