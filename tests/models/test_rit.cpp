// The rendering information transform: identity at initialization (a CG-enhanced network built
// from a trained backbone computes exactly the backbone's output), gates, shapes, inputs.
#include <gtest/gtest.h>

#include <functional>

#include "core/error.h"
#include "models/importance/channel_importance.h"
#include "models/fused_graph.h"
#include "models/inherit.h"
#include "models/sr_network.h"
#include "render_data/augment.h"
#include "tests/models/model_cases.h"

using namespace cgsr;
using namespace cgsr::test;

// A network with the RIT output option `option` set and the same network without it, reading
// `channels`; the RIT's fusion randomized, every parameter the plain one has shared.
std::pair<SRNetwork, SRNetwork> with_and_without(ArchSpec spec, std::vector<std::string> channels, bool RitSpec::*option) {
  spec.rit.channels = std::move(channels);
  const ArchSpec plain_spec = resolve_spec(spec);
  spec = plain_spec;
  spec.rit.*option = true;
  SRNetwork plain(plain_spec), net(resolve_spec(spec));
  randomize_fusion(*plain, 0.1);
  torch::NoGradGuard no_grad;
  auto theirs = plain->named_parameters();
  for (auto& p : net->named_parameters())
    if (theirs.contains(p.key())) p.value().copy_(theirs[p.key()]);
  return {plain, net};
}

TEST(Rit, EnhancedNetworkEqualsItsBackboneAtInitialization) {
  torch::manual_seed(3);
  for (const auto& c : all_backbone_cases()) {
    SRNetwork backbone(spec_for(c));
    for (const auto& source : cgsr::test::rit_sources_for(c.backbone))
      for (const char* fusion : {"concat", "add"}) {
        SCOPED_TRACE(case_name(c) + " " + source + " " + fusion);
        const ArchSpec cg = with_rit(spec_for(c), source, fusion, cgsr::test::has_hr_features(c.backbone));
        auto child = inherit(*backbone, cg);
        EXPECT_FALSE(child.fresh.empty());
        const auto [color, info] = random_inputs(cg, 6, 5);
        torch::NoGradGuard no_grad;
        EXPECT_TRUE(torch::equal(child.network->forward(color, info), backbone->forward(color)));
      }
  }
}

TEST(Rit, InfoChangesTheOutputOnceTheFusionLearns) {
  torch::manual_seed(4);
  SRNetwork net(with_rit(default_spec("pan", 2)));
  const auto [color, info] = random_inputs(net->spec(), 6, 6);
  torch::NoGradGuard no_grad;
  const auto before = net->forward(color, info);
  net->rit()->fuse->weight.normal_(0, 0.1);
  EXPECT_FALSE(torch::equal(net->forward(color, info), before));
  // A zero gate switches the rendering information off entirely.
  net->rit()->gate.zero_();
  const auto gated = net->forward(color, info);
  EXPECT_TRUE(torch::equal(gated, net->forward(color, torch::rand_like(info))));
}

TEST(Rit, GateIsAParameterWithOneEntryPerInputChannel) {
  SRNetwork net(with_rit(default_spec("edsr", 2)));
  const auto gate = net->rit_gate();
  ASSERT_TRUE(gate.defined());
  EXPECT_EQ(gate.numel(), 6);  // depth 1 + normal 3 + normal_angle 1 + edge 1
  EXPECT_TRUE(gate.requires_grad());
  EXPECT_TRUE(torch::equal(gate, torch::ones({6})));
  EXPECT_FALSE(SRNetwork(default_spec("edsr", 2))->rit_gate().defined());
}

TEST(Rit, JointLossGradientsReachGateAndImportances) {
  torch::manual_seed(5);
  SRNetwork net(with_rit(default_spec("pan", 2), "lr", "concat", true));
  {
    torch::NoGradGuard no_grad;
    net->rit()->fuse->weight.normal_(0, 0.1);
  }
  const auto [color, info] = random_inputs(net->spec(), 6, 6);
  const auto out = net->forward_train(color, info);
  ASSERT_TRUE(out.geometry.defined());
  EXPECT_EQ(out.geometry.sizes().vec(), (std::vector<int64_t>{1, 6, 12, 12}));
  const auto importance = channel_importance(*net);
  ASSERT_TRUE(importance.count("block0_a"));
  EXPECT_EQ(importance.at("block0_a").numel(), 20);
  EXPECT_EQ(importance.at("features").numel(), 40);
  EXPECT_EQ(importance.at("rit").numel(), 16);
  EXPECT_FALSE(importance.count("geometry"));
  const auto loss = out.image.mean() + out.geometry.abs().mean() + net->rit_gate().abs().sum() +
                    importance.at("block0_a").index_select(0, torch::tensor({0, 3})).sum();
  loss.backward();
  EXPECT_GT(net->rit_gate().grad().abs().sum().item<float>(), 0.f);
  const torch::Tensor k = net->named_parameters()["backbone.blocks.0.conv1_a.weight"];
  ASSERT_TRUE(k.grad().defined());
  EXPECT_GT(k.grad()[0].abs().sum().item<float>(), 0.f);
}

TEST(Rit, ImportanceIsTheL1NormOfProducingWeights) {
  SRNetwork net(default_spec("edsr", 2));
  const auto imp = channel_importance(*net);
  const auto p = net->named_parameters();
  const auto& w = p["backbone.blocks.2.conv1.weight"];
  const auto& b = p["backbone.blocks.2.conv1.bias"];
  EXPECT_TRUE(torch::allclose(imp.at("block2_mid"), w.abs().sum({1, 2, 3}) + b.abs()));
  // up1 (pixel shuffle): each channel sums its 4 sub-channels.
  const auto& uw = p["backbone.upsample1.weight"];
  const auto& ub = p["backbone.upsample1.bias"];
  const auto per_position = uw.abs().sum({1, 2, 3}) + ub.abs();
  EXPECT_TRUE(torch::allclose(imp.at("up1"), per_position.view({64, 4}).sum(1)));
}

TEST(Rit, WrongInfoShapesAreClearErrors) {
  SRNetwork lr(with_rit(default_spec("pan", 2)));
  const auto color = torch::rand({1, 3, 4, 4});
  EXPECT_THROW(lr->forward(color), Error);
  EXPECT_THROW(lr->forward(color, torch::rand({1, 6, 8, 8})), Error);
  for (const auto& source : rit_sources()) {
    if (source == "lr") continue;
    SRNetwork hr(with_rit(default_spec("pan", 2), source));
    EXPECT_NO_THROW(hr->forward(color, torch::rand({1, 6, 8, 8}))) << source;
    EXPECT_THROW(hr->forward(color, torch::rand({1, 6, 4, 4})), Error) << source;
    EXPECT_TRUE(hr->describe().has_input("info_hr")) << source;
  }
  try {
    lr->forward(color, torch::rand({1, 5, 4, 4}));
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("depth, normal, normal_angle, edge"), std::string::npos) << e.what();
  }
}

TEST(Rit, NetworkTakesItsChannelsFromABatch) {
  ArchSpec s = default_spec("pan", 2);
  s.rit.enabled = true;
  s.rit.channels = {"edge", "depth"};
  s.geometry.enabled = true;
  s = resolve_spec(s);
  EXPECT_EQ(s.rit.channels, (std::vector<std::string>{"depth", "edge"}));  // canonical order
  SRNetwork net(s);
  Batch batch;
  batch.scale = 2;
  batch.channels = {RenderChannel::Depth, RenderChannel::Normal, RenderChannel::Edge};
  batch.lr_info = torch::arange(5).view({1, 5, 1, 1}).expand({1, 5, 3, 3}).to(torch::kFloat);
  batch.hr_info = torch::arange(5).view({1, 5, 1, 1}).expand({1, 5, 6, 6}).to(torch::kFloat);
  const auto info = net->info_input(batch);
  EXPECT_EQ(info.sizes().vec(), (std::vector<int64_t>{1, 2, 3, 3}));
  EXPECT_EQ(info[0][0][0][0].item<float>(), 0.f);  // depth
  EXPECT_EQ(info[0][1][0][0].item<float>(), 4.f);  // edge, after the 3 normal channels
  EXPECT_EQ(net->geometry_target(batch).sizes().vec(), (std::vector<int64_t>{1, 2, 6, 6}));
  batch.channels = {RenderChannel::Depth};
  batch.lr_info = torch::zeros({1, 1, 3, 3});
  try {
    net->info_input(batch);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("'edge'"), std::string::npos) << e.what();
  }
}

TEST(Rit, HrUnshuffleIsSpaceToDepthThenConv3x3OnTheLrGrid) {
  // The strided conv of hr_unshuffle must equal the paper-style formulation: pixel_unshuffle of
  // the HR map (LR pixel (i, j) <- HR pixels s*i.. s*i+s-1, s*j.. s*j+s-1), then a 3x3 conv.
  torch::manual_seed(21);
  for (int s : {2, 3, 4}) {
    SCOPED_TRACE(s);
    SRNetwork net(with_rit(default_spec("pan", s), "hr_unshuffle"));
    auto conv = net->rit()->conv;
    const int64_t c = 6, w = conv->weight.size(0);
    ASSERT_EQ(conv->weight.sizes().vec(), (std::vector<int64_t>{w, c, 3 * s, 3 * s}));
    // [w, c, 3 (ky), s (a), 3 (kx), s (b)] -> [w, c, a, b, ky, kx] -> [w, c*s*s, 3, 3]
    const auto unshuffled_weight = conv->weight.view({w, c, 3, s, 3, s}).permute({0, 1, 3, 5, 2, 4}).reshape({w, c * s * s, 3, 3});
    const auto info = torch::rand({1, c, 5 * s, 7 * s});
    torch::NoGradGuard no_grad;
    const auto strided = conv(info);
    const auto reference = torch::conv2d(torch::pixel_unshuffle(info, s), unshuffled_weight, conv->bias, 1, 1);
    ASSERT_EQ(strided.sizes().vec(), (std::vector<int64_t>{1, w, 5, 7}));
    EXPECT_TRUE(torch::allclose(strided, reference, 1e-5, 1e-5));
    // Moving the HR map by one LR pixel moves the features by one LR pixel; by one HR pixel it does not.
    const auto by_lr_pixel = conv(torch::roll(info, {s}, {3}));
    EXPECT_TRUE(torch::allclose(by_lr_pixel.slice(3, 2, 6), strided.slice(3, 1, 5), 1e-5, 1e-5));
    const auto by_hr_pixel = conv(torch::roll(info, {1}, {3}));
    EXPECT_FALSE(torch::allclose(by_hr_pixel.slice(3, 2, 6), strided.slice(3, 1, 5), 1e-3, 1e-3));
  }
}

TEST(Rit, HrFusionReadsGeometryAtTheOutputPixel) {
  // With hr_conv reduced to its centre tap, an edge at one HR pixel reaches exactly as far as the
  // backbone's convolutions after the fusion point, the same distance on every side: a branch
  // off by one pixel (or fused before the last upsampling) would not be symmetric or would reach
  // further.
  torch::manual_seed(22);
  const std::vector<std::pair<const char*, int64_t>> reach = {{"pan", 2}, {"edsr", 1}, {"srcnn", 2}};
  for (const auto& [backbone, r] : reach)
    for (int s : {2, 3, 4}) {
      SCOPED_TRACE(std::string(backbone) + " x" + std::to_string(s));
      SRNetwork net(with_rit(default_spec(backbone, s), "hr_fuse"));
      randomize_fusion(*net, 0.2);
      net->eval();
      torch::NoGradGuard no_grad;
      auto& w = net->rit()->hr_conv->weight;
      const auto centre = w.slice(2, 1, 2).slice(3, 1, 2).clone();
      w.zero_();
      w.slice(2, 1, 2).slice(3, 1, 2).copy_(centre);
      const int64_t h = 5, wd = 5, y = 2 * s + 1, x = 2 * s;
      const auto color = torch::rand({1, 3, h, wd});
      auto info = torch::zeros({1, 6, h * s, wd * s});
      const auto base = net->forward(color, info);
      info[0][5][y][x] = 1;  // the edge channel
      const auto diff = (net->forward(color, info) - base).abs().sum(0).sum(0);
      for (const auto& [dy, dx] : std::vector<std::pair<int64_t, int64_t>>{{0, 0}, {-r, 0}, {r, 0}, {0, -r}, {0, r}})
        EXPECT_GT(diff[y + dy][x + dx].item<float>(), 0.f) << dy << "," << dx;
      auto outside = diff.clone();
      outside.slice(0, y - r, y + r + 1).slice(1, x - r, x + r + 1).zero_();
      EXPECT_EQ(outside.max().item<float>(), 0.f);
    }
}

TEST(Rit, BatchesInAnotherDepthEncodingAreRefused) {
  SRNetwork net(with_rit(default_spec("pan", 2)));
  Batch batch;
  batch.scale = 2;
  batch.channels = {RenderChannel::Depth, RenderChannel::Normal, RenderChannel::NormalAngle, RenderChannel::Edge};
  batch.lr_info = torch::rand({1, 6, 3, 3});
  batch.hr_info = torch::rand({1, 6, 6, 6});
  batch.depth_encoding = DepthEncoding::Log;
  EXPECT_NO_THROW(net->info_input(batch));
  batch.depth_encoding = DepthEncoding::ZBuffer;
  try {
    net->info_input(batch);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("zbuffer-encoded, the model reads log"), std::string::npos) << e.what();
  }
  // Without depth among the channels the encoding does not matter.
  ArchSpec no_depth = with_rit(default_spec("pan", 2));
  no_depth.rit.channels = {"edge"};
  SRNetwork edges(resolve_spec(no_depth));
  EXPECT_NO_THROW(edges->info_input(batch));
}

// rit.bsp_composite over every backbone, scale and HR source: the output is the bsp channel's
// colour, bit for bit, on the pixels its coverage marks, and the same network without the option
// elsewhere; the graph computes what forward() does; the covered pixels give the network no
// gradient (training learns the rest).
TEST(Rit, BspCompositeIsTheBspImageWhereCoveredAndTheNetworkElsewhere) {
  torch::manual_seed(23);
  for (const auto& c : all_backbone_cases())
    for (const auto& source : rit_sources_for(c.backbone)) {
      if (source == "lr") continue;
      SCOPED_TRACE(case_name(c) + " " + source);
      // bsp at positions 1..4: the selection's offset counts
      auto [plain, net] = with_and_without(with_rit(spec_for(c), source), {"edge", "bsp"}, &RitSpec::bsp_composite);
      auto [color, info] = random_inputs(net->spec(), 7, 5);
      info.select(1, 4).copy_(torch::rand_like(info.select(1, 4)).gt(0.6));  // coverage: 0 or 1
      const auto covered = info.slice(1, 4, 5).expand({-1, 3, -1, -1}).to(torch::kBool);
      const auto bsp = info.slice(1, 1, 4);
      ASSERT_GT(covered.sum().item<int64_t>(), 0);
      ASSERT_GT((~covered).sum().item<int64_t>(), 0);
      {
        torch::NoGradGuard no_grad;
        const auto out = net->forward(color, info), theirs = plain->forward(color, info);
        EXPECT_TRUE(torch::equal(out.masked_select(covered), bsp.masked_select(covered)));
        EXPECT_TRUE(torch::equal(out.masked_select(~covered), theirs.masked_select(~covered)));
        EXPECT_FALSE(torch::equal(out, theirs));
      }
      // The interpreter runs the composite as forward() does, in the deployed graph too.
      {
        torch::NoGradGuard no_grad;
        const auto g = net->describe(/*training=*/true);
        const auto image = graph::run(g, network_inputs(g, color, info)).front().second;
        EXPECT_TRUE(torch::equal(image, net->forward_train(color, info).image));
        const auto deployed = net->describe(/*training=*/false);
        EXPECT_NE(deployed.find_op("rit.bsp_color"), nullptr);
        const auto served = graph::run(deployed, network_inputs(deployed, color, info)).front().second;
        EXPECT_TRUE(torch::equal(served.masked_select(covered), bsp.masked_select(covered)));
      }
      // A loss on the covered pixels only reaches no parameter.
      net->zero_grad();
      net->forward_train(color, info).image.masked_select(covered).sum().backward();
      for (const auto& p : net->parameters()) {
        if (p.grad().defined()) {
          EXPECT_EQ(p.grad().abs().max().item<float>(), 0.f);
        }
      }
      // The composite holds no parameters: the model file and the parameter count are unchanged.
      EXPECT_EQ(total_parameter_count(*net), total_parameter_count(*plain));
      EXPECT_EQ(inference_parameter_count(*net), inference_parameter_count(*plain));
    }
}

// rit.history_blend over every backbone, scale and HR source: where the history channel has no
// sample (recency 0) the output is the same network's without the option, bit for bit; where it
// has one, a blend weight driven high gives the sample; the graph computes what forward() does;
// the blend's conv (3 outputs over the image and the info) is its only parameter.
TEST(Rit, HistoryBlendIsTheNetworkWithoutASampleAndLearnsToTakeOne) {
  torch::manual_seed(29);
  for (const auto& c : all_backbone_cases())
    for (const auto& source : rit_sources_for(c.backbone)) {
      if (source == "lr") continue;
      SCOPED_TRACE(case_name(c) + " " + source);
      // history at positions 1..4: the offset counts
      auto [plain, net] = with_and_without(with_rit(spec_for(c), source), {"edge", "history"}, &RitSpec::history_blend);
      auto [color, info] = random_inputs(net->spec(), 7, 5);
      // Recency: 0 (no sample) or one of the ages' values.
      const auto age = torch::randint(0, 6, info.select(1, 4).sizes());
      info.select(1, 4).copy_(torch::where(age.eq(5), torch::zeros_like(age), 1.0 - age / 5.0).to(torch::kFloat));
      const auto empty = info.slice(1, 4, 5).expand({-1, 3, -1, -1}).eq(0);
      const auto sampled = ~empty;
      const auto history = info.slice(1, 1, 4);
      ASSERT_GT(empty.sum().item<int64_t>(), 0);
      ASSERT_GT(sampled.sum().item<int64_t>(), 0);
      {
        torch::NoGradGuard no_grad;
        const auto out = net->forward(color, info), theirs = plain->forward(color, info);
        EXPECT_TRUE(torch::equal(out.masked_select(empty), theirs.masked_select(empty)));
        // A fresh blend barely moves the network's image (weight sigmoid(-4) * recency < 0.02).
        EXPECT_LT((out - theirs).abs().max().item<float>(), 0.02f * ((history - theirs).abs().max().item<float>() + 1e-6f));
        EXPECT_FALSE(torch::equal(out, theirs));
        // A weight of about 1 on the current frame's samples (recency 1) gives them.
        net->rit()->blend->bias.fill_(30.0f);
        const auto current = info.slice(1, 4, 5).expand({-1, 3, -1, -1}).eq(1);
        const auto taken = net->forward(color, info);
        EXPECT_TRUE(torch::allclose(taken.masked_select(current), history.masked_select(current), 1e-5, 1e-5));
      }
      // The interpreter runs the blend as forward() does, in the deployed graph too.
      {
        torch::NoGradGuard no_grad;
        const auto g = net->describe(/*training=*/true);
        const auto image = graph::run(g, network_inputs(g, color, info)).front().second;
        EXPECT_TRUE(torch::equal(image, net->forward_train(color, info).image));
        // Deployed (branch convs folded), it is the plain network's deployed graph without a
        // sample and the sample where its weight is 1.
        const auto deployed = net->describe(/*training=*/false), plain_deployed = plain->describe(false);
        EXPECT_NE(deployed.find_op("rit.blend"), nullptr);
        const auto served = graph::run(deployed, network_inputs(deployed, color, info)).front().second;
        const auto theirs = graph::run(plain_deployed, network_inputs(plain_deployed, color, info)).front().second;
        EXPECT_TRUE(torch::equal(served.masked_select(empty), theirs.masked_select(empty)));
        const auto current = info.slice(1, 4, 5).expand({-1, 3, -1, -1}).eq(1);
        EXPECT_TRUE(torch::allclose(served.masked_select(current), history.masked_select(current), 1e-5, 1e-5));
      }
      // The blend's conv is the only new parameter: (3 + 5) * 3 * 9 weights and 3 biases.
      EXPECT_EQ(total_parameter_count(*net), total_parameter_count(*plain) + 8 * 3 * 9 + 3);
    }
}

// `t` moved by `by` pixels along `axis` (0: x, 1: y): pixel i reads i + by, the last column or row
// repeating.
torch::Tensor moved_by(const torch::Tensor& t, int axis, int64_t by) {
  const int dim = axis == 0 ? 3 : 2;
  const int64_t n = t.size(dim);
  return torch::cat({t.narrow(dim, by, n - by), t.narrow(dim, n - 1, 1).expand_as(t.narrow(dim, 0, by))}, dim);
}

// An HR image without its outer LR pixel (s HR pixels), where interpolations clamp differently.
torch::Tensor inner(const torch::Tensor& t, int64_t s) {
  return t.narrow(2, s, t.size(2) - 2 * s).narrow(3, s, t.size(3) - 2 * s);
}

// `spec` with and without the jitter option `option`, reading edge and jitter (the jitter at info
// channels 1, 2, so the offset counts): no parameter is added and at jitter 0 both compute the
// same; `check(plain, net, color, info, axis)` then runs with a jitter of one whole LR pixel along x
// (axis 0), then y; last, at a random jitter, the training graph computes exactly what forward()
// does and the deployed graph the same within 1e-5.
using JitterCheck = std::function<void(SRNetwork& plain, SRNetwork& net, const torch::Tensor& color,
                                       const torch::Tensor& info, int axis)>;
void check_jitter_option(const ArchSpec& spec, bool RitSpec::*option, const JitterCheck& check) {
  auto [plain, net] = with_and_without(spec, {"edge", "jitter"}, option);
  EXPECT_EQ(total_parameter_count(*net), total_parameter_count(*plain));
  auto [color, info] = random_inputs(net->spec(), 9, 7);
  torch::NoGradGuard no_grad;
  info.narrow(1, 1, 2).zero_();
  EXPECT_TRUE(torch::allclose(net->forward(color, info), plain->forward(color, info), 1e-5, 1e-5));
  for (int axis : {0, 1}) {
    SCOPED_TRACE(axis == 0 ? "x" : "y");
    info.narrow(1, 1, 2).zero_();
    info.select(1, 1 + axis).fill_(1.0f);
    check(plain, net, color, info, axis);
  }
  info.narrow(1, 1, 2).uniform_(-0.5, 0.5);
  const auto out = net->forward(color, info);
  const auto g = net->describe(/*training=*/true);
  EXPECT_TRUE(torch::equal(graph::run(g, network_inputs(g, color, info)).front().second, out));
  const auto deployed = net->describe(/*training=*/false);
  EXPECT_TRUE(
      torch::allclose(graph::run(deployed, network_inputs(deployed, color, info)).front().second, out, 1e-5, 1e-5));
}

// rit.skip_at_jitter at every scale and HR source: a jitter of one whole LR pixel reads the skip
// one LR pixel over (x right, y down), so away from the border the output moves by the skip of the
// shifted image.
TEST(Rit, SkipAtJitterMovesPansSkipToTheJitter) {
  torch::manual_seed(31);
  for (int scale : {2, 3, 4})
    for (const auto& source : rit_sources_for("pan")) {
      if (source == "lr") continue;
      SCOPED_TRACE(std::to_string(scale) + " " + source);
      const auto skip = [&](const torch::Tensor& lr) { return graph::apply_resize(lr, scale, graph::ResizeMode::Bilinear); };
      check_jitter_option(with_rit(default_spec("pan", scale), source), &RitSpec::skip_at_jitter,
                          [&](SRNetwork& plain, SRNetwork& net, const torch::Tensor& color, const torch::Tensor& info,
                              int axis) {
                            const auto moved = inner(net->forward(color, info) - plain->forward(color, info), scale);
                            const auto expected = inner(skip(moved_by(color, axis, 1)) - skip(color), scale);
                            EXPECT_TRUE(torch::allclose(moved, expected, 1e-4, 1e-4))
                                << (moved - expected).abs().max().item<float>();
                          });
    }
}

// rit.residual_at_jitter: a jitter of one whole LR pixel moves the skip as above and the residual
// over it by s HR pixels, so away from the border the output is the skip of the shifted image plus
// the skip_at_jitter network's residual, shifted.
TEST(Rit, ResidualAtJitterMovesTheWholeOutput) {
  torch::manual_seed(41);
  for (int scale : {2, 3}) {
    SCOPED_TRACE(scale);
    ArchSpec spec = with_rit(default_spec("pan", scale), "hr_unshuffle+hr_fuse");
    spec.rit.skip_at_jitter = true;
    const auto skip = [&](const torch::Tensor& lr) { return graph::apply_resize(lr, scale, graph::ResizeMode::Bilinear); };
    check_jitter_option(spec, &RitSpec::residual_at_jitter,
                        [&](SRNetwork& plain, SRNetwork& net, const torch::Tensor& color, const torch::Tensor& info,
                            int axis) {
                          // The plain network on this info (the jitter planes are RIT inputs too)
                          // adds its residual to the moved skip; this one moves that residual too.
                          const auto skip_moved = plain->forward(color, info);
                          const auto moved_skip = skip(moved_by(color, axis, 1));
                          const auto expected =
                              inner(moved_skip + moved_by(skip_moved - moved_skip, axis, scale), scale);
                          const auto out = inner(net->forward(color, info), scale);
                          EXPECT_TRUE(torch::allclose(out, expected, 1e-4, 1e-4))
                              << (out - expected).abs().max().item<float>();
                          EXPECT_FALSE(torch::allclose(out, inner(skip_moved, scale), 1e-3, 1e-3));
                        });
  }
}

// The training augmentations keep the skip at the jitter right: flipping or rotating a frame and
// transforming its jitter like a motion vector (render_data/augment.h) gives the interpolation of
// the flipped or rotated frame.
TEST(Rit, AugmentedJitterSamplesTheAugmentedFrame) {
  torch::manual_seed(37);
  const int64_t s = 2;
  const auto lr = torch::rand({1, 3, 6, 6});
  auto planes = torch::empty({1, 2, 12, 12});
  planes.select(1, 0).fill_(0.3f);
  planes.select(1, 1).fill_(-0.2f);
  const auto sampled = graph::apply_sample(lr, planes, s, graph::ResizeMode::Bilinear);
  for (int i = 0; i < 8; ++i) {
    SCOPED_TRACE(i);
    const Augmentation a = Augmentation::from_index(i);
    const auto moved_planes = augment_info(planes, {RenderChannel::Jitter}, a);
    const auto of_moved = graph::apply_sample(augment_image(lr, a), moved_planes, s, graph::ResizeMode::Bilinear);
    EXPECT_TRUE(torch::allclose(of_moved, augment_image(sampled, a), 1e-5, 1e-5));
  }
}

// rit.history_warp bicubic: the previous output read at whole-pixel motion is the pixel itself, as
// with bilinear; at half a pixel the two filters differ, and the network's warp is the graph op's
// bicubic sample; graph, forward() and the fused path agree.
TEST(Rit, HistoryWarpBicubicResamplesThePreviousOutput) {
  torch::manual_seed(43);
  const auto c = all_backbone_cases().front();
  auto spec = with_rit(spec_for(c), "hr_fuse");
  spec.rit.channels = {"edge", "history_out"};
  spec.rit.history_blend = true;
  auto bicubic_spec = spec;
  bicubic_spec.rit.history_warp = WarpFilter::Bicubic;
  SRNetwork bilinear(resolve_spec(spec)), bicubic(resolve_spec(bicubic_spec));
  torch::NoGradGuard no_grad;
  auto theirs = bilinear->named_parameters();
  for (auto& p : bicubic->named_parameters()) p.value().copy_(theirs[p.key()]);
  for (SRNetwork* net : {&bilinear, &bicubic}) (*net)->rit()->blend->bias.fill_(30.0f);  // the output is the warp
  auto [color, info] = random_inputs(bicubic->spec(), 7, 5);
  info.select(1, 4).fill_(1.0f);  // valid everywhere
  info.select(1, 5).fill_(1.0f);
  info.select(1, 6).zero_();
  const auto whole = bicubic->forward(color, info);
  EXPECT_TRUE(torch::allclose(whole, bilinear->forward(color, info), 1e-5, 1e-5));
  EXPECT_TRUE(torch::allclose(whole, moved_by(info.slice(1, 1, 4), 0, 1), 1e-5, 1e-5));
  info.select(1, 5).fill_(0.5f);
  const auto half = bicubic->forward(color, info);
  EXPECT_GT((half - bilinear->forward(color, info)).abs().max().item<float>(), 1e-3);
  const auto expected = graph::apply_sample(info.slice(1, 1, 4), info.slice(1, 5, 7), 1, graph::ResizeMode::Bicubic);
  EXPECT_TRUE(torch::allclose(half, expected, 1e-5, 1e-5));
  const auto deployed = bicubic->describe(/*training=*/false);
  const auto served = graph::run(deployed, network_inputs(deployed, color, info)).front().second;
  EXPECT_TRUE(torch::equal(served, half));
  FusedGraph fused(deployed);
  EXPECT_TRUE(torch::allclose(fused.run(color, info), served, 1e-4, 1e-4));
}

// history_out (the network's own previous output, planes 1-3 here, its validity 4, its motion 5-6)
// over every backbone, scale and HR source: where no pixel is valid the previous colour changes
// nothing, bit for bit; where some are it does; a blend weight driven high gives the previous
// output read at p + motion (a pixel moved 1 to the right reads its right neighbour), in the
// deployed graph too; the graph computes what forward() does, the fused path what the deployed
// graph does.
TEST(Rit, HistoryOutWarpsThePreviousOutputWhereValid) {
  torch::manual_seed(41);
  for (const auto& c : all_backbone_cases())
    for (const auto& source : rit_sources_for(c.backbone)) {
      if (source == "lr") continue;
      SCOPED_TRACE(case_name(c) + " " + source);
      auto [plain, net] = with_and_without(with_rit(spec_for(c), source), {"edge", "history_out"}, &RitSpec::history_blend);
      auto [color, info] = random_inputs(net->spec(), 7, 5);
      info.select(1, 5).fill_(1.0f);
      info.select(1, 6).zero_();
      info.select(1, 4).copy_(torch::randint(0, 2, info.select(1, 4).sizes()).to(torch::kFloat));
      torch::NoGradGuard no_grad;
      auto none = info.clone();
      none.select(1, 4).zero_();
      auto other = none.clone();
      other.slice(1, 1, 4).uniform_(0, 1);
      EXPECT_TRUE(torch::equal(net->forward(color, none), net->forward(color, other)));
      EXPECT_TRUE(torch::equal(plain->forward(color, none), plain->forward(color, other)));
      auto changed = info.clone();
      changed.slice(1, 1, 4).uniform_(0, 1);
      EXPECT_FALSE(torch::equal(plain->forward(color, info), plain->forward(color, changed)));
      EXPECT_FALSE(torch::equal(net->forward(color, info), net->forward(color, changed)));

      net->rit()->blend->bias.fill_(30.0f);
      const auto valid = info.slice(1, 4, 5).expand({-1, 3, -1, -1}).eq(1);
      const auto warped = moved_by(info.slice(1, 1, 4), 0, 1);
      const auto taken = net->forward(color, info);
      EXPECT_TRUE(torch::allclose(taken.masked_select(valid), warped.masked_select(valid), 1e-5, 1e-5));
      const auto g = net->describe(/*training=*/true);
      EXPECT_TRUE(torch::equal(graph::run(g, network_inputs(g, color, info)).front().second,
                               net->forward_train(color, info).image));
      const auto deployed = net->describe(/*training=*/false);
      const auto served = graph::run(deployed, network_inputs(deployed, color, info)).front().second;
      EXPECT_TRUE(torch::allclose(served.masked_select(valid), warped.masked_select(valid), 1e-5, 1e-5));
      FusedGraph fused(deployed);
      const auto fast = fused.run(color, info);
      EXPECT_TRUE(torch::allclose(fast, served, 1e-4, 1e-4)) << (fast - served).abs().max().item<float>();
    }
}

// rit.feature_channels: the convolutions read the listed channels alone (here edge, the second of
// the information's channels), with fewer weights; an unlisted channel changes nothing unless an
// option reads it.
TEST(Rit, FeatureChannelsAreAllTheConvolutionsRead) {
  torch::manual_seed(43);
  for (const auto& source : rit_sources_for("pan")) {
    SCOPED_TRACE(source);
    ArchSpec spec = with_rit(default_spec("pan", 4), source);
    spec.rit.channels = {"depth", "edge"};
    const ArchSpec all = resolve_spec(spec);
    spec.rit.feature_channels = {"edge"};
    SRNetwork net(resolve_spec(spec)), wide(all);
    EXPECT_LT(total_parameter_count(*net), total_parameter_count(*wide));
    randomize_fusion(*net, 0.1);
    const auto [color, info] = random_inputs(net->spec(), 7, 5);
    torch::NoGradGuard no_grad;
    const auto out = net->forward(color, info);
    auto depth = info.clone();
    depth.select(1, 0).uniform_(0, 1);
    EXPECT_TRUE(torch::equal(net->forward(color, depth), out));
    auto edge = info.clone();
    edge.select(1, 1).uniform_(0, 1);
    EXPECT_FALSE(torch::equal(net->forward(color, edge), out));
    const auto deployed = net->describe(/*training=*/false);
    const auto served = graph::run(deployed, network_inputs(deployed, color, info)).front().second;
    EXPECT_TRUE(torch::allclose(served, out, 1e-5, 1e-5)) << (served - out).abs().max().item<float>();
    FusedGraph fused(deployed);
    const auto fast = fused.run(color, info);
    EXPECT_TRUE(torch::allclose(fast, out, 1e-4, 1e-4)) << (fast - out).abs().max().item<float>();
  }
}
