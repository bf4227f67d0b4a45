// Static baselines: the importance registry, magnitude pruning (per group, the channels whose
// producing weights are smallest go), pruning to a rate along any order, and the rate for a MACs
// budget.
#include <gtest/gtest.h>

#include <algorithm>

#include "core/error.h"
#include "models/complexity.h"
#include "models/importance/importance_methods.h"
#include "pruning/baseline_pruning.h"
#include "tests/pruning/pruning_cases.h"

using namespace cgsr;
using namespace cgsr::test;

TEST(MagnitudePruning, RemovesTheSmallestChannels) {
  torch::manual_seed(10);
  SRNetwork net(small_spec("edsr", 2, 2, 6, 8));
  randomize(*net);
  {
    // Make channels 1 and 4 of block0's middle group the weakest (their conv1 rows tiny).
    torch::NoGradGuard no_grad;
    auto params = net->named_parameters();
    auto w = params["backbone.blocks.0.conv1.weight"], b = params["backbone.blocks.0.conv1.bias"];
    w.abs_().add_(0.05);
    b.abs_();
    for (int c : {1, 4, 2}) {
      w[c].mul_(c == 2 ? 0.3 : 0.01);
      b[c].mul_(c == 2 ? 0.3 : 0.01);
    }
  }
  Inheritance pruned = magnitude_prune(*net, 0.5);  // keeps 3 of 6
  EXPECT_EQ(pruned.kept.at("block0_mid"), (std::vector<int64_t>{0, 3, 5}));
  EXPECT_EQ(pruned.network->spec().group_width("block0_mid"), 3);
  EXPECT_EQ(pruned.network->spec().group_width("block1_mid"), 3);
  EXPECT_EQ(pruned.network->spec().group_width("up1"), 3);
  EXPECT_EQ(pruned.network->spec().group_width("features"), 8);  // residual stream untouched
  // Same structure as a dynamic pattern of the same rate: the masked dense reference.
  const auto [color, info] = inputs_for(*net, 5, 4);
  torch::NoGradGuard no_grad;
  EXPECT_LT(max_diff(pruned.network->forward(color), masked_dense(*net, pruned.kept, color, info)), 1e-5);
}

TEST(ImportanceMethods, OneRegistryScoresEveryUnitGroup) {
  EXPECT_EQ(importance_methods().names(), (std::vector<std::string>{"activation", "magnitude", "taylor"}));
  try {
    importance_methods().get("tailor");
    FAIL() << "an unknown method must be an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("did you mean 'taylor'"), std::string::npos) << e.what();
  }
  torch::manual_seed(12);
  SRNetwork net(small_spec("pan", 2, 2, 6, 8));
  randomize(*net);
  const auto units = find_units(net->describe(false));
  Batch b;
  b.scale = 2;
  b.lr_color = torch::rand({1, 3, 6, 5});
  b.hr_color = torch::rand({1, 3, 12, 10});
  b.frames = {0};
  const auto reference = channel_importance(*net);
  for (const auto& name : importance_methods().names()) {
    SCOPED_TRACE(name);
    const FrameImportance scores = importance_methods().get(name).score(*net, b, unit_groups(units));
    for (const auto& u : units)
      for (size_t g = 0; g < u.groups.size(); ++g) {
        ASSERT_TRUE(scores.count(u.groups[g]));
        EXPECT_EQ(scores.at(u.groups[g]).numel(), u.widths[g]);
        EXPECT_TRUE(torch::isfinite(scores.at(u.groups[g])).all().item<bool>());
        if (name == "magnitude") {
          EXPECT_TRUE(torch::allclose(scores.at(u.groups[g]), reference.at(u.groups[g])));
        }
      }
  }
}

TEST(BaselinePruning, KeepsTheFirstChannelsOfTheOrderInTheirOwnOrder) {
  torch::manual_seed(13);
  SRNetwork net(small_spec("edsr", 2, 2, 6, 8));
  randomize(*net);
  const auto units = find_units(net->describe(false));
  const ChannelSelection order = random_order(units, 4);
  Inheritance pruned = prune_to_rate(*net, order, 0.5);  // 3 of 6
  for (const auto& u : units)
    for (const auto& g : u.groups) {
      std::vector<int64_t> expected(order.at(g).begin(), order.at(g).begin() + 3);
      std::sort(expected.begin(), expected.end());
      EXPECT_EQ(pruned.kept.at(g), expected) << g;
    }
  const auto [color, info] = inputs_for(*net, 5, 4);
  torch::NoGradGuard no_grad;
  EXPECT_LT(max_diff(pruned.network->forward(color), masked_dense(*net, pruned.kept, color, info)), 1e-5);
  EXPECT_THROW(prune_to_rate(*net, order, 0.0), Error);

  // A rate matched to MACs never costs more than asked, and the next larger rate would.
  const int64_t budget = complexity(*net, 16, 12).macs / 2;
  const double rate = keep_rate_for_macs(*net, budget, 16, 12);
  EXPECT_LE(complexity(*magnitude_prune(*net, rate).network, 16, 12).macs, budget);
  EXPECT_GT(complexity(*magnitude_prune(*net, std::min(1.0, rate + 0.2)).network, 16, 12).macs, budget);
}

TEST(BaselinePruning, LabelsAndConfig) {
  EXPECT_EQ(baseline_label({"magnitude", 0}), "MMP");
  EXPECT_EQ(baseline_label({"taylor", 0.5}), "taylor pruning 0.50");
  const auto parsed = config::parse_document(config::Document::parse("type: activation\nkeep_rate: 0.3\n", "b.yaml"),
                                             baseline_schema());
  EXPECT_EQ(parsed.type, "activation");
  EXPECT_DOUBLE_EQ(parsed.keep_rate, 0.3);
  EXPECT_THROW(config::parse_document(config::Document::parse("type: l2\n", "b.yaml"), baseline_schema()),
               Error);
}
