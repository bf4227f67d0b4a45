// Pattern pools of subnets: chosen from a search front around the pick, their union, and the
// pool moved into the network the union builds, where every pattern computes the same.
#include <gtest/gtest.h>

#include "core/error.h"
#include "models/backbone_registry.h"
#include "pruning/pattern_pool.h"
#include "tests/pruning/pruning_cases.h"

using namespace cgsr;
using namespace cgsr::test;

namespace {
// A front of subnets with the given predicted latencies (fastest first).
std::vector<Candidate> front_of(const PatternPool& pool) {
  std::vector<Candidate> front;
  for (int k = pool.size(); k-- > 0;) {
    Candidate c;
    c.subnet = pool.patterns[k];
    c.score.latency_ms = 10.0 * (pool.size() - k);
    front.push_back(c);
  }
  return front;
}
}  // namespace

TEST(PatternPool, PointsOfTheFrontNearestTheLatencyFactorsWidestFirst) {
  SRNetwork net(small_spec("pan", 2, 3, 6, 8, true));
  const PatternPool drawn = random_pool(*net, 6, 1);
  const auto front = front_of(drawn);  // latencies 10, 20, ..., 60
  PoolOptions options;
  options.latency_factors = {2.0, 1.0, 0.5};
  const PatternPool pool = pool_from_front(net->spec(), front, 30, options);
  ASSERT_EQ(pool.size(), 3);
  EXPECT_EQ(pool.patterns[0], front[5].subnet);  // 60 ms
  EXPECT_EQ(pool.patterns[1], front[2].subnet);  // 30 ms
  EXPECT_EQ(pool.patterns[2], front[0].subnet);  // 15 ms: 10 is nearest among those left
  // Each point is used once: more factors than points give fewer patterns.
  options.latency_factors = {1.02, 1.01, 1.0, 0.99, 0.98, 0.97, 0.96};
  EXPECT_EQ(pool_from_front(net->spec(), front, 30, options).size(), 6);
  EXPECT_THROW(pool_from_front(net->spec(), {}, 30, options), Error);
}

TEST(PatternPool, TheUnionHoldsEveryPatternAndRebasedPatternsComputeTheSame) {
  for (const auto& c : net_cases()) {
    SCOPED_TRACE(c.name);
    torch::manual_seed(4);
    SRNetwork net(c.spec);
    randomize(*net);
    net->eval();
    const PatternPool pool = random_pool(*net, 3, 7);
    const SubnetConfig all = pool_union(pool);
    for (const auto& p : pool.patterns) {
      for (int b : p.blocks) EXPECT_TRUE(std::binary_search(all.blocks.begin(), all.blocks.end(), b));
      for (const auto& [group, width] : p.widths) {
        const auto block = parse_block_group(group);
        if (!block || std::binary_search(p.blocks.begin(), p.blocks.end(), block->first)) {
          EXPECT_LE(width, all.widths.at(group)) << group;
        }
      }
    }
    SRNetwork small = materialize_subnet(*net, all, false);
    small->eval();
    const PatternPool moved = rebase_pool(pool, all, small->spec());
    const auto [color, info] = inputs_for(*net, 7, 5);
    for (int k = 0; k < pool.size(); ++k)
      EXPECT_LT(max_diff(run_pattern(*net, pool, k, color, info), run_pattern(*small, moved, k, color, info)), 1e-5);
  }
}

TEST(PatternPool, ChosenPatternsJsonAndChannelFraction) {
  SRNetwork net(small_spec("pan", 2, 2, 6, 8));
  const PatternPool pool = random_pool(*net, 3, 2);
  std::vector<int> kept;
  const PatternPool chosen = chosen_patterns(pool, {4, 0, 1}, kept);
  EXPECT_EQ(kept, (std::vector<int>{0, 2}));
  EXPECT_EQ(chosen.patterns[1], pool.patterns[2]);
  EXPECT_THROW(chosen_patterns(pool, {0, 0, 0}, kept), Error);

  const PatternPool back = pool_from_json(to_json(pool), net->spec(), "pool.json");
  EXPECT_EQ(back.patterns, pool.patterns);
  auto bad = to_json(pool);
  bad["patterns"][0]["widths"]["features"] = 99;
  EXPECT_THROW(pool_from_json(bad, net->spec(), "pool.json"), Error);
  EXPECT_THROW(pool_from_json(nlohmann::ordered_json{{"patterns", nlohmann::ordered_json::array()}}, net->spec(), "p"),
               Error);

  PatternPool full = pool;
  full.patterns = {full_subnet(net->spec())};
  EXPECT_DOUBLE_EQ(full.channel_fraction(0), 1.0);
  for (int k = 0; k < pool.size(); ++k) EXPECT_LT(pool.channel_fraction(k), 1.0);
}
