// Structural re-parameterization (models/reparameterization.h) and SPAN, the backbone that uses it.

#include <gtest/gtest.h>
#include <torch/torch.h>

#include "core/error.h"
#include "models/backbones/span.h"
#include "models/complexity.h"
#include "models/reparameterization.h"
#include "tests/models/model_cases.h"

namespace cgsr {
namespace {

ConvTensors random_conv(int64_t out, int64_t in, int64_t k) {
  return {torch::randn({out, in, k, k}) * 0.3, torch::randn({out}) * 0.3};
}

double relative_error(const torch::Tensor& a, const torch::Tensor& b) {
  return (a - b).abs().max().item<double>() / std::max(1.0, b.abs().max().item<double>());
}

TEST(Reparameterization, FoldedConvEqualsItsBranchesBorderIncluded) {
  torch::manual_seed(0);
  const auto expand = random_conv(10, 4, 1), spatial = random_conv(12, 10, 3), squeeze = random_conv(6, 12, 1),
             skip = random_conv(6, 4, 1);
  const auto x = torch::randn({2, 4, 7, 5});
  const auto branches = torch::conv2d(
      torch::conv2d(torch::conv2d(x, expand.weight, expand.bias, 1, 1), spatial.weight, spatial.bias), squeeze.weight,
      squeeze.bias) + torch::conv2d(x, skip.weight, skip.bias);
  const auto folded = fold_branches(expand, spatial, squeeze, skip);
  EXPECT_EQ(folded.weight.sizes().vec(), (std::vector<int64_t>{6, 4, 3, 3}));
  const auto y = torch::conv2d(x, folded.weight, folded.bias, 1, 1);
  EXPECT_LT(relative_error(y, branches), 1e-5);
  // Padding the expand conv's input is what makes the fold exact: padding its output instead
  // (zeros where the branch sees its bias) gives the same interior and other border pixels.
  const auto padded_later = torch::conv2d(
      torch::conv2d(torch::conv2d(x, expand.weight, expand.bias), spatial.weight, spatial.bias, 1, 1), squeeze.weight,
      squeeze.bias) + torch::conv2d(x, skip.weight, skip.bias);
  const auto interior = [](const torch::Tensor& t) { return t.slice(2, 1, -1).slice(3, 1, -1); };
  EXPECT_LT(relative_error(interior(padded_later), interior(branches)), 1e-5);
  EXPECT_GT(relative_error(padded_later.select(2, 0), branches.select(2, 0)), 1e-3);
}

TEST(Reparameterization, GraphsWithoutBranchesAreUnchanged) {
  for (const char* backbone : {"pan", "edsr", "srcnn"}) {
    SRNetwork net(default_spec(backbone, 2));
    const auto branches = net->describe_branches();
    const auto folded = net->describe(false);
    ASSERT_EQ(folded.ops.size(), branches.ops.size()) << backbone;
    for (size_t i = 0; i < folded.ops.size(); ++i) EXPECT_EQ(folded.ops[i].name, branches.ops[i].name);
  }
}

// The figures: the reference implementation's deployed convolutions.
TEST(Span, DeployedParameterCountsMatchTheReference) {
  const auto params = [](int scale, int features) {
    ArchSpec s = default_spec("span", scale);
    s.widths = {};
    s = resolve_spec(s);
    for (const auto& [group, width] : s.widths.entries()) s.widths.set(group, features);
    return inference_parameter_count(*SRNetwork(s));
  };
  EXPECT_EQ(params(2, 48), 410700);
  EXPECT_EQ(params(4, 48), 426288);
  EXPECT_EQ(params(4, 28), 150688);
}

TEST(Span, TrainedBranchesAndTheirFoldComputeTheSame) {
  torch::manual_seed(3);
  for (int scale : {2, 4}) {
    SRNetwork net(test::with_rit(default_spec("span", scale), "hr_unshuffle"));
    test::randomize_fusion(*net, 0.1);
    const auto [color, info] = test::random_inputs(net->spec(), 11, 9);
    torch::NoGradGuard no_grad;
    net->train();
    const auto branches = net->forward(color, info);
    net->eval();
    const auto folded = net->forward(color, info);
    EXPECT_LT(relative_error(folded, branches), 1e-5);
    // The inference graph is the folded network: one conv per re-parameterizable conv.
    const auto g = net->describe(false);
    const auto out = graph::run(g, network_inputs(g, color, info)).front().second;
    EXPECT_TRUE(torch::equal(out, folded));
    int convs = 0;
    for (const auto& op : g.ops) convs += op.kind == graph::OpKind::Conv;
    EXPECT_EQ(convs, 1 + 6 * 3 + 1 + 2 + 2);  // conv_1, the blocks, conv_2, conv_cat, upsampler, the RIT's two
    EXPECT_NE(g.find_op("backbone.blocks.5.c3_r"), nullptr);
  }
}

TEST(Span, RefusesWhatNeedsHrFeatures) {
  const ArchSpec span = default_spec("span", 2);
  for (const char* source : {"hr_fuse", "hr_unshuffle+hr_fuse"}) {
    try {
      SRNetwork net(test::with_rit(span, source));
      FAIL() << source << " accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("no HR feature map"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(SRNetwork(test::with_rit(span, "lr", "concat", /*geometry=*/true)), Error);
}

}  // namespace
}  // namespace cgsr
