// The oneDNN inference path computes what the interpreter computes (up to float rounding) for
// every backbone, RIT variants and pruned widths, at any input size, and rejects wrong inputs.
#include <gtest/gtest.h>

#include <algorithm>

#include "core/error.h"
#include "models/backbone_registry.h"
#include "models/fused_graph.h"
#include "models/sr_network.h"
#include "tests/models/model_cases.h"

using namespace cgsr;
using namespace cgsr::test;

namespace {

using Inputs = std::vector<std::pair<std::string, torch::Tensor>>;

Inputs inputs_of(const ArchSpec& spec, int64_t n, int64_t h, int64_t w,
                 const std::function<torch::Tensor(std::vector<int64_t>)>& make) {
  Inputs in = {{"color", make({n, 3, h, w})}};
  if (spec.rit.enabled) {
    const int64_t f = spec.rit.reads_hr() ? spec.scale : 1;
    in.emplace_back(spec.rit.reads_hr() ? "info_hr" : "info",
                    make({n, static_cast<int64_t>(spec.rit.info_width()), h * f, w * f}));
  }
  return in;
}

Inputs random_of(const ArchSpec& spec, int64_t n, int64_t h, int64_t w) {
  return inputs_of(spec, n, h, w, [](std::vector<int64_t> s) { return torch::rand(s); });
}

double max_abs_diff(const torch::Tensor& a, const torch::Tensor& b) {
  return (a - b).abs().max().item<double>();
}

// Largest differences seen by the comparisons of the running test (printed at its end).
double largest_relative = 0, largest_absolute = 0;

// Runs the fused graph and the interpreter on the same inputs; the outputs agree to `tolerance`
// relative to the output's magnitude when it exceeds 1 (inputs of 1e3 give outputs near 1e3,
// where float32 values are 6e-5 apart: no other summation order stays within 1e-4 of them).
void expect_equal_outputs(FusedGraph& fused, const graph::Graph& g, const Inputs& in, double tolerance = 1e-4) {
  torch::NoGradGuard no_grad;
  const auto expected = graph::run(g, in);
  const auto got = fused.run(in);
  ASSERT_EQ(got.size(), expected.size());
  for (size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].first, expected[i].first);
    ASSERT_EQ(got[i].second.sizes(), expected[i].second.sizes());
    EXPECT_TRUE(got[i].second.is_contiguous());
    EXPECT_EQ(got[i].second.scalar_type(), torch::kFloat);
    const double scale = std::max(1.0, expected[i].second.abs().max().item<double>());
    const double diff = max_abs_diff(got[i].second, expected[i].second);
    largest_relative = std::max(largest_relative, diff / scale);
    largest_absolute = std::max(largest_absolute, diff);
    EXPECT_LE(diff, tolerance * scale) << "output " << got[i].first << " of magnitude " << scale;
  }
}

// One image 12x17, then a batch of two (a second plan).
void expect_network_matches(const ArchSpec& spec, uint64_t seed, FusedGraph::Options options = FusedGraph::Options()) {
  SRNetwork net = build_network(spec, seed);
  const graph::Graph g = net->describe();
  FusedGraph fused(g, options);
  expect_equal_outputs(fused, g, random_of(spec, 1, 12, 17));
  expect_equal_outputs(fused, g, random_of(spec, 2, 12, 17));
}

// Widths as pruning and the search leave them: odd, and not multiples of a SIMD block.
ArchSpec reduced_pan(int scale) {
  ArchSpec s = default_spec("pan", scale);
  s.blocks = 2;
  s.widths = GroupWidths();
  s.widths.set("features", 13);
  s.widths.set("block0_a", 7);
  s.widths.set("block0_a_out", 9);
  s.widths.set("block0_b", 5);
  s.widths.set("block0_att", 11);
  s.widths.set("block0_b_out", 6);
  s.widths.set("block1_a", 3);
  s.widths.set("block1_b_out", 1);
  s.widths.set("up1", 7);
  s.widths.set("hr1", 13);
  if (scale == 4) {
    s.widths.set("up2", 5);
    s.widths.set("hr2", 9);
  }
  s.rit.width = 7;
  return resolve_spec(s);
}

ArchSpec reduced_edsr(int scale) {
  ArchSpec s = default_spec("edsr", scale);
  s.blocks = 2;
  s.widths = GroupWidths();
  s.widths.set("features", 13);
  s.widths.set("block0_mid", 7);
  s.widths.set("up1", 5);
  return resolve_spec(s);
}

ArchSpec reduced_srcnn(int scale) {
  ArchSpec s = default_spec("srcnn", scale);
  s.widths = GroupWidths();
  s.widths.set("conv1", 13);
  s.widths.set("conv2", 7);
  return resolve_spec(s);
}

}  // namespace

class FusedGraphTest : public ::testing::Test {
 protected:
  void SetUp() override { largest_relative = largest_absolute = 0; }
  void TearDown() override {
    std::printf("largest difference to graph::run: %.3g (%.3g relative to the output's magnitude)\n",
                largest_absolute, largest_relative);
  }
};

TEST_F(FusedGraphTest, EveryBackboneAtEveryScale) {
  uint64_t seed = 10;
  for (const auto& name : backbone_registry().names())
    for (int scale : {2, 3, 4}) {
      ArchSpec spec = default_spec(name, scale);
      SCOPED_TRACE(name + " x" + std::to_string(scale));
      expect_network_matches(spec, ++seed);
      if (backbone_registry().get(name).supports_y) {
        spec.colors = Colors::Y;
        SCOPED_TRACE("luma");
        expect_network_matches(resolve_spec(spec), ++seed);
      }
    }
}

// SRPO's sampling by offsets and its mask run as LibTorch steps inside the plan; with offsets of
// several pixels (trained-looking, not the near-zero ones of a fresh network) many pixels move,
// and the plan picks the pixels the interpreter picks.
TEST_F(FusedGraphTest, SrpoWithOffsetsOfSeveralPixels) {
  uint64_t seed = 70;
  for (int scale : {2, 3, 4}) {
    SCOPED_TRACE("srpo x" + std::to_string(scale));
    SRNetwork net = build_network(default_spec("srpo", scale), ++seed);
    {
      torch::NoGradGuard no_grad;
      net->named_parameters()["backbone.conv3.weight"].mul_(30);
    }
    const graph::Graph g = net->describe();
    FusedGraph fused(g);
    const auto in = random_of(net->spec(), 2, 12, 17);
    expect_equal_outputs(fused, g, in);
    torch::NoGradGuard no_grad;
    const auto bicubic = graph::apply_resize(in[0].second, scale, graph::ResizeMode::Bicubic);
    EXPECT_GT((fused.run(in)[0].second - bicubic).abs().gt(1e-3).sum().item<int64_t>(), 100);
  }
}

// A bicubic image skip runs as a LibTorch step inside the plan (oneDNN resamples nearest and
// linear only).
TEST_F(FusedGraphTest, BicubicImageSkip) {
  uint64_t seed = 30;
  for (int scale : {2, 3, 4}) {
    SCOPED_TRACE("x" + std::to_string(scale));
    ArchSpec spec = default_spec("pan", scale);
    spec.image_skip = ImageSkip::Bicubic;
    expect_network_matches(spec, ++seed);
    expect_network_matches(with_rit(spec, "hr_unshuffle+hr_fuse", "concat"), ++seed);
  }
}

TEST_F(FusedGraphTest, RitVariants) {
  uint64_t seed = 40;
  for (const char* b : {"pan", "edsr", "srcnn"})
    for (const auto& source : rit_sources())
      for (const char* fusion : {"concat", "add"}) {
        const int scale = fusion[0] == 'c' ? 2 : 4;
        SCOPED_TRACE(std::string(b) + " x" + std::to_string(scale) + " " + source + " " + fusion);
        expect_network_matches(with_rit(default_spec(b, scale), source, fusion), ++seed);
      }
}

TEST_F(FusedGraphTest, ReducedOddWidths) {
  uint64_t seed = 70;
  for (int scale : {2, 3, 4}) {
    SCOPED_TRACE("x" + std::to_string(scale));
    expect_network_matches(reduced_pan(scale), ++seed);
    expect_network_matches(with_rit(reduced_pan(scale), "hr_pooled", "concat"), ++seed);
    expect_network_matches(reduced_edsr(scale), ++seed);
    expect_network_matches(reduced_srcnn(scale), ++seed);
  }
}

// Every design the options select computes the same, including the blocked layout whose padded
// channels (widths 13, 7) must never leak into results.
TEST_F(FusedGraphTest, EveryOptionComputesTheSame) {
  uint64_t seed = 90;
  for (const ArchSpec& spec : {with_rit(reduced_pan(4), "lr", "concat"), reduced_edsr(3),
                               with_rit(reduced_srcnn(2), "hr_pooled", "concat")}) {
    SRNetwork net = build_network(spec, ++seed);
    const graph::Graph g = net->describe();
    const Inputs in = random_of(spec, 2, 7, 9);
    // The defaults, each option flipped alone, all of them flipped.
    for (int flipped : {0, 1, 2, 4, 8, 16, 31}) {
      FusedGraph::Options options;
      if (flipped & 1) options.layout = FusedGraph::Layout::Blocked;
      options.fuse ^= static_cast<bool>(flipped & 2);
      options.split_concat ^= static_cast<bool>(flipped & 4);
      options.sum_in_place ^= static_cast<bool>(flipped & 8);
      options.tune ^= static_cast<bool>(flipped & 16);
      SCOPED_TRACE(spec.backbone + " options flipped " + std::to_string(flipped));
      FusedGraph fused(g, options);
      expect_equal_outputs(fused, g, in);
    }
  }
}

TEST_F(FusedGraphTest, ExtremeInputs) {
  uint64_t seed = 120;
  for (const ArchSpec& spec : {with_rit(default_spec("pan", 2), "lr", "concat"), default_spec("edsr", 3),
                               default_spec("srcnn", 4), with_rit(reduced_pan(4), "hr_pooled", "add")}) {
    SCOPED_TRACE(spec.backbone);
    SRNetwork net = build_network(spec, ++seed);
    const graph::Graph g = net->describe();
    FusedGraph fused(g);
    for (float value : {0.f, 1.f, 1e3f}) {
      SCOPED_TRACE(value);
      expect_equal_outputs(fused, g, inputs_of(spec, 2, 9, 11, [&](std::vector<int64_t> s) {
                             return torch::full(s, value);
                           }));
    }
    expect_equal_outputs(fused, g, inputs_of(spec, 1, 9, 11, [](std::vector<int64_t> s) {
                           return torch::randn(s) * 1e3;
                         }));
  }
}

TEST_F(FusedGraphTest, TinyInputsAndRecompilingForNewSizes) {
  uint64_t seed = 140;
  for (const ArchSpec& spec : {with_rit(default_spec("pan", 3), "hr_pooled", "concat"), default_spec("edsr", 4),
                               default_spec("srcnn", 2)}) {
    SCOPED_TRACE(spec.backbone);
    SRNetwork net = build_network(spec, ++seed);
    const graph::Graph g = net->describe();
    FusedGraph::Options options;
    options.cached_plans = 2;
    FusedGraph fused(g, options);
    for (auto [n, h, w] : {std::tuple{1, 1, 1}, {1, 2, 2}, {2, 12, 17}, {1, 5, 3}, {1, 2, 2}, {2, 12, 17}}) {
      SCOPED_TRACE(std::to_string(n) + "x" + std::to_string(h) + "x" + std::to_string(w));
      expect_equal_outputs(fused, g, random_of(spec, n, h, w));
    }
  }
}

TEST_F(FusedGraphTest, SnapshotOfTheWeights) {
  SRNetwork net = build_network(default_spec("pan", 2), 160);
  FusedGraph fused(net->describe());
  const auto color = torch::rand({1, 3, 6, 7});
  const auto before = fused.run(color);
  {
    torch::NoGradGuard no_grad;
    net->named_parameters()["backbone.conv_last.weight"].add_(1.0);
  }
  EXPECT_TRUE(torch::equal(fused.run(color), before));  // recompile (construct again) after training
  torch::NoGradGuard no_grad;
  EXPECT_FALSE(torch::allclose(FusedGraph(net->describe()).run(color), before));
}

// PAN's element-wise ops all end up inside convolutions, and no step needs a reference kernel.
TEST_F(FusedGraphTest, PanPlanFusesAttentionAndResiduals) {
  SRNetwork net = build_network(with_rit(default_spec("pan", 2), "lr", "concat"), 170);
  const graph::Graph g = net->describe();
  FusedGraph fused(g);
  fused.run(random_of(net->spec(), 1, 8, 8));
  const auto& steps = fused.steps();
  const auto step_of = [&](const std::string& op) -> const FusedGraph::Step* {
    for (const auto& s : steps)
      if (std::find(s.ops.begin(), s.ops.end(), op) != s.ops.end()) return &s;
    return nullptr;
  };
  for (const auto& s : steps) {
    EXPECT_EQ(s.implementation.find("ref"), std::string::npos) << s.kind << " " << s.ops[0];
    EXPECT_TRUE(s.kind == "conv" || s.kind == "resampling" || s.kind == "binary" || s.kind == "pooling")
        << s.kind << " " << s.ops[0];
  }
  // x * sigmoid(conv(x)), then LeakyReLU: one step.
  const auto* att = step_of("backbone.att1.conv");
  ASSERT_NE(att, nullptr);
  EXPECT_EQ(att->kind, "conv");
  EXPECT_EQ(att->ops.size(), 4u);
  // k3(x) * sigmoid(k2(x)): the product rides on one of the two convolutions.
  const auto* k2 = step_of("backbone.blocks.0.pa_conv.k2");
  const auto* k3 = step_of("backbone.blocks.0.pa_conv.k3");
  ASSERT_TRUE(k2 && k3);
  EXPECT_EQ(k2->ops.size() + k3->ops.size(), 4u);
  // conv3(cat(a, b)) + x: the concatenation is never built, the residual is a post-op.
  const auto* conv3 = step_of("backbone.blocks.0.conv3");
  ASSERT_NE(conv3, nullptr);
  EXPECT_EQ(conv3->ops.size(), 3u);
  // conv_last + bilinear(color).
  EXPECT_EQ(step_of("backbone.conv_last")->ops.size(), 2u);
  int convs = 0;
  for (const auto& op : g.ops) convs += op.kind == graph::OpKind::Conv;
  EXPECT_LT(steps.size(), static_cast<size_t>(convs + 6));
  EXPECT_FALSE(fused.plan_string().empty());
}

TEST_F(FusedGraphTest, WrongInputsAreErrors) {
  const ArchSpec spec = with_rit(default_spec("pan", 2), "hr_pooled", "concat");
  SRNetwork net = build_network(spec, 180);
  FusedGraph fused(net->describe());
  const auto color = torch::rand({1, 3, 6, 5});
  const auto info = torch::rand({1, 6, 12, 10});
  EXPECT_NO_THROW(fused.run(color, info));
  EXPECT_THROW(fused.run(color), Error);                                                       // no info
  EXPECT_THROW(fused.run({{"colour", color}, {"info_hr", info}}), Error);                      // unknown name
  EXPECT_THROW(fused.run({{"color", color}, {"info", info}}), Error);                          // LR name
  EXPECT_THROW(fused.run({{"color", color}, {"info_hr", info}, {"info_hr", info}}), Error);    // twice
  EXPECT_THROW(fused.run(torch::rand({1, 4, 6, 5}), info), Error);                             // channels
  EXPECT_THROW(fused.run(torch::rand({3, 6, 5}), info), Error);                                // 3-D
  EXPECT_THROW(fused.run(color, torch::rand({1, 6, 6, 5})), Error);                            // info at LR
  EXPECT_THROW(fused.run(color, torch::rand({2, 6, 12, 10})), Error);                          // batch
  EXPECT_THROW(fused.run(color.to(torch::kDouble), info), Error);                              // type
  EXPECT_THROW(fused.run(torch::rand({1, 3, 0, 5}), torch::rand({1, 6, 0, 10})), Error);       // empty
  FusedGraph plain(build_network(default_spec("edsr", 2), 181)->describe());
  EXPECT_THROW(plain.run(color, info), Error);  // a network without RIT takes no info
  // Non-contiguous inputs are fine.
  const auto wide = torch::rand({1, 3, 5, 6}).transpose(2, 3);
  EXPECT_TRUE(torch::allclose(plain.run(wide), plain.run(wide.contiguous())));
}
