// The magnitude baseline removes, per group, the channels whose producing weights are smallest.
#include <gtest/gtest.h>

#include "pruning/magnitude_pruning.h"
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
