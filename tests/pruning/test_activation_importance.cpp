// Per-frame channel importance: channels that cannot change the output score zero, the ranking
// follows activation size, and the network is left as it was found.
#include <gtest/gtest.h>

#include "models/importance/activation_importance.h"
#include "tests/pruning/pruning_cases.h"

using namespace cgsr;
using namespace cgsr::test;

namespace {
Batch batch_for(const SRNetworkImpl& net, int64_t w, int64_t h) {
  Batch b;
  b.scale = net.spec().scale;
  b.lr_color = torch::rand({1, 3, h, w});
  b.hr_color = torch::rand({1, 3, h * b.scale, w * b.scale});
  b.frames = {0};
  return b;
}
}  // namespace

TEST(ActivationImportance, UnreadAndSilentChannelsScoreZero) {
  torch::manual_seed(14);
  SRNetwork net(small_spec("edsr", 2, 1, 6, 8));
  randomize(*net);
  auto params = net->named_parameters();
  {
    torch::NoGradGuard no_grad;
    params["backbone.blocks.0.conv2.weight"].select(1, 2).zero_();  // channel 2 is never read
    params["backbone.blocks.0.conv1.weight"][4].zero_();            // channel 4 is always 0
    params["backbone.blocks.0.conv1.bias"][4] = 0.0f;
  }
  const auto units = find_units(net->describe(false));
  const Batch b = batch_for(*net, 6, 5);
  net->train();
  const auto taylor = frame_importance(*net, b, unit_groups(units), ActivationScore::Taylor);
  const auto active = frame_importance(*net, b, unit_groups(units), ActivationScore::MeanAbsolute);
  EXPECT_TRUE(net->is_training());
  for (const auto& p : net->parameters()) EXPECT_FALSE(p.grad().defined());
  const auto t = taylor.at("block0_mid"), a = active.at("block0_mid");
  ASSERT_EQ(t.numel(), 6);
  EXPECT_EQ(t[2].item<float>(), 0.0f);
  EXPECT_EQ(t[4].item<float>(), 0.0f);
  EXPECT_EQ(a[4].item<float>(), 0.0f);
  EXPECT_GT(a[2].item<float>(), 0.0f);  // it is active, only unread
  EXPECT_GT(t.sum().item<float>(), 0.0f);
  EXPECT_EQ(taylor.at("up1").numel(), 6);
}

TEST(ActivationImportance, ActivationMethodIsTheMeanMagnitude) {
  torch::manual_seed(15);
  SRNetwork net(small_spec("srcnn", 2, 0, 5, 4));
  randomize(*net);
  const auto units = find_units(net->describe(false));
  const Batch b = batch_for(*net, 8, 8);
  const auto active = frame_importance(*net, b, unit_groups(units), ActivationScore::MeanAbsolute);
  // The value conv2 reads: the activated conv1 output; recompute it with the graph.
  const auto g = net->describe(false);
  torch::Tensor conv2_input;
  const auto* conv2 = g.find_op("backbone.conv2");
  ASSERT_NE(conv2, nullptr);
  torch::NoGradGuard no_grad;
  graph::run(g, {{"color", b.lr_color}}, nullptr, [&](size_t i, const torch::Tensor& y) {
    if (g.ops[i].output == conv2->inputs[0]) conv2_input = y;
    return y;
  });
  ASSERT_TRUE(conv2_input.defined());
  EXPECT_TRUE(torch::allclose(active.at("conv1"), conv2_input.abs().mean({0, 2, 3})));
}
