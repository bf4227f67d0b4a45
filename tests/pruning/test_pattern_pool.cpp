// Frequency-based sorting on controlled per-frame importance: the pool holds the most frequent
// patterns, merges near-identical ones by the documented rule, and assigns frames to the nearest.
#include <gtest/gtest.h>

#include "core/error.h"
#include "pruning/pattern_pool.h"

using namespace cgsr;

namespace {
PrunableUnit two_groups() {
  PrunableUnit u;
  u.name = "block0";
  u.groups = {"block0_a", "block0_b"};
  u.widths = {4, 4};
  return u;
}

// Importance favouring channels `a` of block0_a and `b` of block0_b.
FrameImportance favour(std::vector<int> a, std::vector<int> b) {
  auto ia = torch::full({4}, 0.1f), ib = torch::full({4}, 0.1f);
  for (size_t i = 0; i < a.size(); ++i) ia[a[i]] = 2.0f - 0.1f * i;
  for (size_t i = 0; i < b.size(); ++i) ib[b[i]] = 2.0f - 0.1f * i;
  return {{"block0_a", ia}, {"block0_b", ib}};
}

std::vector<FrameImportance> controlled_frames() {
  std::vector<FrameImportance> f;
  for (int i = 0; i < 5; ++i) f.push_back(favour({0, 1}, {0, 1}));
  for (int i = 0; i < 3; ++i) f.push_back(favour({2, 3}, {2, 3}));
  f.push_back(favour({0, 1}, {0, 2}));  // frame 8: one channel off the first pattern
  f.push_back(favour({2, 3}, {1, 3}));  // frame 9: one channel off the second
  return f;
}

using Keep = std::vector<int64_t>;
}  // namespace

TEST(PatternPool, TopChannelsPerGroup) {
  const auto keep = top_channels(two_groups(), favour({3, 1}, {2, 0}), 0.5);
  EXPECT_EQ(keep.at("block0_a"), (Keep{1, 3}));
  EXPECT_EQ(keep.at("block0_b"), (Keep{0, 2}));
}

TEST(PatternPool, MostFrequentExactPatterns) {
  PoolOptions o;
  o.keep_rate = 0.5;
  o.size = 2;
  o.merge_tolerance = 0;
  const auto build = build_pattern_pool({two_groups()}, controlled_frames(), o);
  const auto& p = build.pool.units.at(0).patterns;
  ASSERT_EQ(p.size(), 2u);
  EXPECT_EQ(p[0].keep.at("block0_a"), (Keep{0, 1}));
  EXPECT_EQ(p[0].keep.at("block0_b"), (Keep{0, 1}));
  EXPECT_EQ(p[1].keep.at("block0_a"), (Keep{2, 3}));
  EXPECT_EQ(p[1].keep.at("block0_b"), (Keep{2, 3}));
  // Frames 8 and 9 join their nearest entries.
  EXPECT_EQ(p[0].frames, 6);
  EXPECT_EQ(p[1].frames, 4);
  EXPECT_EQ(build.assignment[8][0], 0);
  EXPECT_EQ(build.assignment[9][0], 1);
  EXPECT_EQ(build.assignment[6][0], 1);
}

TEST(PatternPool, RarePatternsFillALargerPool) {
  PoolOptions o;
  o.keep_rate = 0.5;
  o.size = 3;
  o.merge_tolerance = 0;
  const auto build = build_pattern_pool({two_groups()}, controlled_frames(), o);
  const auto& p = build.pool.units.at(0).patterns;
  ASSERT_EQ(p.size(), 3u);
  // The third entry is frame 8's pattern (tie with frame 9 broken by the earlier frame).
  EXPECT_EQ(p[2].keep.at("block0_b"), (Keep{0, 2}));
  EXPECT_EQ(p[0].frames, 5);
  EXPECT_EQ(p[1].frames, 4);
  EXPECT_EQ(p[2].frames, 1);
}

TEST(PatternPool, NearIdenticalPatternsMergeIntoTheirConsensus) {
  std::vector<FrameImportance> f = {favour({0, 1}, {0, 1}), favour({0, 1}, {0, 1}), favour({0, 1}, {0, 2}),
                                    favour({0, 1}, {0, 3}), favour({2, 3}, {2, 3})};
  PoolOptions o;
  o.keep_rate = 0.5;
  o.size = 4;
  o.merge_tolerance = 0.25;  // one of the 4 kept channels may differ
  const auto build = build_pattern_pool({two_groups()}, f, o);
  const auto& p = build.pool.units.at(0).patterns;
  ASSERT_EQ(p.size(), 2u);  // frames 0-3 form one cluster
  EXPECT_EQ(p[0].frames, 4);
  EXPECT_EQ(p[0].keep.at("block0_b"), (Keep{0, 1}));  // 0 chosen 4 times, 1 twice
  EXPECT_EQ(p[1].frames, 1);
}

TEST(PatternPool, UnionAndJsonRoundTrip) {
  PoolOptions o;
  o.keep_rate = 0.5;
  o.size = 2;
  const auto build = build_pattern_pool({two_groups()}, controlled_frames(), o);
  const auto all = build.pool.union_selection();
  EXPECT_EQ(all.at("block0_a"), (Keep{0, 1, 2, 3}));
  EXPECT_EQ(build.pool.selection({1}).at("block0_b"), (Keep{2, 3}));
  const auto back = pool_from_json(to_json(build.pool), {two_groups()}, "test");
  EXPECT_EQ(to_json(back), to_json(build.pool));
  auto other = two_groups();
  other.widths = {4, 5};
  EXPECT_THROW(pool_from_json(to_json(build.pool), {other}, "test"), Error);
  auto broken = to_json(build.pool);
  broken["units"][0]["patterns"][0]["keep"]["block0_a"] = {3, 1};
  EXPECT_THROW(pool_from_json(broken, {two_groups()}, "test"), Error);
}
