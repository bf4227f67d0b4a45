// Dynamic samplers: input from current and previous rendering information, scores per unit,
// padding never chosen, dropped patterns leave the remaining choices unchanged.
#include <gtest/gtest.h>

#include "core/error.h"
#include "pruning/dynamic_sampler.h"

using namespace cgsr;

TEST(DynamicSampler, InputPoolsCurrentAndChange) {
  const auto channels = parse_channels({"depth", "motion"});
  const auto info = torch::rand({1, 3, 12, 20}), previous = torch::rand({1, 3, 12, 20});
  const auto x = sampler_input(info, previous, channels, 4);
  ASSERT_EQ(x.sizes(), (std::vector<int64_t>{1, 6, 4, 4}));
  // Depth averaged over 3x5 cells; motion divided by the frame size (20 wide, 12 high).
  EXPECT_NEAR(x[0][0][0][0].item<float>(), info[0][0].slice(0, 0, 3).slice(1, 0, 5).mean().item<float>(), 1e-6);
  EXPECT_NEAR(x[0][1][1][2].item<float>() * 20, info[0][1].slice(0, 3, 6).slice(1, 10, 15).mean().item<float>(),
              1e-5);
  EXPECT_NEAR(x[0][5][0][0].item<float>() * 12,
              (info[0][2] - previous[0][2]).slice(0, 0, 3).slice(1, 0, 5).mean().item<float>(), 1e-5);
  EXPECT_TRUE(torch::equal(sampler_input(info, {}, channels, 4).slice(1, 3, 6), torch::zeros({1, 3, 4, 4})));
  EXPECT_THROW(sampler_input(torch::rand({1, 2, 8, 8}), {}, channels, 4), Error);
}

TEST(DynamicSampler, ScoresAndChoices) {
  torch::manual_seed(12);
  SamplerOptions o;
  o.channels = {"depth", "edge"};
  o.grid = 8;
  o.width = 4;
  DynamicSamplers s(o, std::vector<int>{3, 1, 5});
  const auto x = torch::rand({6, 4, 8, 8});
  const auto scores = s->forward(x);
  ASSERT_EQ(scores.sizes(), (std::vector<int64_t>{6, 3, 5}));
  const auto choices = s->choose(x);
  for (const auto& c : choices) {
    EXPECT_LT(c[0], 3);
    EXPECT_EQ(c[1], 0);
    EXPECT_LT(c[2], 5);
  }
  EXPECT_EQ(s->macs(), s->conv1->weight.numel() * 64 + s->conv2->weight.numel() * 16 + s->head->weight.numel());
}

TEST(DynamicSampler, KeepingPatternsPreservesTheirScores) {
  torch::manual_seed(13);
  SamplerOptions o;
  o.channels = {"depth"};
  o.grid = 6;
  DynamicSamplers s(o, std::vector<int>{4, 3});
  const auto x = torch::rand({5, 2, 6, 6});
  torch::NoGradGuard no_grad;
  const auto before = s->forward(x);
  s->keep_patterns({{3, 1}, {2}});
  const auto after = s->forward(x);
  ASSERT_EQ(after.sizes(), (std::vector<int64_t>{5, 2, 2}));
  EXPECT_TRUE(torch::allclose(after.select(1, 0).select(1, 0), before.select(1, 0).select(1, 3)));
  EXPECT_TRUE(torch::allclose(after.select(1, 0).select(1, 1), before.select(1, 0).select(1, 1)));
  EXPECT_TRUE(torch::allclose(after.select(1, 1).select(1, 0), before.select(1, 1).select(1, 2)));
  EXPECT_LT(after[0][1][1].item<float>(), -1e8);  // padding of the one-pattern unit
  EXPECT_EQ(s->patterns(), (std::vector<int>{2, 1}));
}
