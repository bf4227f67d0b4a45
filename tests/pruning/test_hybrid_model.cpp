// Hybrid model files: the static network loads as a plain model, the dynamic pruning component
// and the latency table round-trip exactly, and the upscaler chooses per frame from current and
// previous rendering information, running the chosen pattern.
#include <gtest/gtest.h>

#include "core/error.h"
#include "pruning/hybrid_model.h"
#include "pruning/hybrid_upscaler.h"
#include "pruning/pattern_networks.h"
#include "pruning/static_pruning.h"
#include "tests/pruning/pruning_cases.h"
#include "tests/support/cli_runner.h"

using namespace cgsr;
using namespace cgsr::test;

namespace {
HybridModel make_hybrid() {
  SRNetwork net(small_spec("pan", 2, 2, 6, 8, /*rit=*/true));
  randomize(*net);
  net->eval();
  const PatternPool pool = random_pool(*net, 4, 6);
  StaticPruning pruned = static_prune(*net, pool, {0, 3, 1, 2});
  SamplerOptions so;
  so.channels = {"depth", "edge"};
  so.grid = 4;
  so.width = 3;
  HybridModel h;
  h.samplers = DynamicSamplers(so, std::vector<int>{pool.size()});
  h.samplers->keep_patterns({pruned.kept});
  h.network = pruned.network;
  h.pool = pruned.pool;
  h.latency = {6, 5, {3.0, 2.0, 1.5}};
  h.provenance.stage = "pruned";
  h.provenance.extra = {{"name", "tiny hybrid"}};
  return h;
}

// A frame with depth, normal_angle and edge (the union of network and sampler channels).
Batch frame(int index, int64_t w = 6, int64_t h = 5) {
  Batch b;
  b.scale = 2;
  b.lr_color = torch::rand({1, 3, h, w});
  b.channels = parse_channels({"depth", "normal_angle", "edge"});
  b.lr_info = torch::rand({1, 3, h, w});
  b.frames = {index};
  return b;
}
}  // namespace

TEST(HybridModel, RoundTripsAndLoadsAsAPlainModel) {
  torch::manual_seed(16);
  const HybridModel h = make_hybrid();
  const auto dir = scratch_dir("hybrid-model");
  const auto path = dir / "pruned.cgsr";
  save_hybrid_model(path, h);

  const Model plain = load_model(path);
  EXPECT_TRUE(is_hybrid_model(plain.provenance));
  EXPECT_EQ(plain.network->spec(), h.network->spec());

  HybridModel loaded = load_hybrid_model(path);
  EXPECT_EQ(to_json(loaded.pool), to_json(h.pool));
  EXPECT_EQ(loaded.latency.median_ms, h.latency.median_ms);
  EXPECT_EQ(loaded.latency.lr_width, 6);
  HybridUpscaler a("a", h), b("b", loaded);
  EXPECT_EQ(b.channels(), parse_channels({"depth", "normal_angle", "edge"}));
  for (int i = 0; i < 3; ++i) {
    const Batch f = frame(i);
    EXPECT_TRUE(torch::equal(a.upscale(f), b.upscale(f)));
    EXPECT_EQ(a.frame_choice()->pattern, b.frame_choice()->pattern);
  }
  // The output is the chosen pattern run on the static network.
  const Batch f = frame(7);
  const auto out = b.upscale(f);
  const int k = b.frame_choice()->pattern;
  PatternNetworks patterns(*loaded.network, loaded.pool);
  EXPECT_TRUE(torch::allclose(out, patterns.run(k, f.lr_color, f.lr_info), 0, 1e-6));
  EXPECT_GE(b.frame_choice()->choose_ms, 0.0);

  save_model(dir / "plain.cgsr", *h.network);
  EXPECT_THROW(load_hybrid_model(dir / "plain.cgsr"), Error);
  std::filesystem::remove_all(dir);
}

TEST(HybridModel, UsesThePreviousFrame) {
  torch::manual_seed(17);
  HybridUpscaler up("h", make_hybrid());
  const Batch f0 = frame(4), f1 = frame(5);
  up.upscale(f1);
  EXPECT_FALSE(up.frame_choice()->previous_frame);
  up.previous_frame(f0);
  up.upscale(f1);
  EXPECT_TRUE(up.frame_choice()->previous_frame);
  // Frame after frame, the last upscaled frame is the previous one.
  up.upscale(f0);
  up.upscale(f1);
  EXPECT_TRUE(up.frame_choice()->previous_frame);
  Batch two = frame(6);  // patterns are chosen per frame: one frame at a time
  two.lr_color = torch::rand({2, 3, 5, 6});
  two.lr_info = torch::rand({2, 3, 5, 6});
  EXPECT_THROW(up.upscale(two), Error);
  const auto cost = up.cost(6, 5);
  ASSERT_TRUE(cost.has_value());
  EXPECT_GT(cost->macs, 0);
}

// The component reads the rendering information: a sampler taught that edge-dense frames need
// the widest pattern and flat ones the narrowest chooses so in the upscaler.
TEST(HybridModel, TheChoiceFollowsTheRenderingInformation) {
  torch::manual_seed(19);
  HybridModel h = make_hybrid();
  const int narrowest = h.pool.size() - 1;
  const auto channels = h.samplers->options().render_channels();
  const auto input_for = [&](float edge) {
    auto info = torch::full({1, 2, 5, 6}, 0.5f);
    info[0][1].fill_(edge);
    return sampler_input(info, {}, channels, h.samplers->options().grid);
  };
  const auto inputs = torch::cat({input_for(1.0f), input_for(0.0f)}, 0);
  const auto target = torch::tensor({int64_t{0}, int64_t{narrowest}});
  torch::optim::Adam optimizer(h.samplers->parameters(), torch::optim::AdamOptions(0.05));
  for (int step = 0; step < 200; ++step) {
    const auto loss = torch::nn::functional::cross_entropy(h.samplers->forward(inputs).select(1, 0), target);
    optimizer.zero_grad();
    loss.backward();
    optimizer.step();
  }
  HybridUpscaler up("h", h);
  Batch edges = frame(1), flat = frame(3);
  edges.lr_info = torch::full({1, 3, 5, 6}, 0.5f);
  edges.lr_info[0][2].fill_(1.0f);
  flat.lr_info = torch::full({1, 3, 5, 6}, 0.5f);
  flat.lr_info[0][2].fill_(0.0f);
  EXPECT_EQ(up.choose(edges), 0);
  EXPECT_EQ(up.choose(flat), narrowest);
  // Mean MACs follow the choices: one frame each of the widest and the narrowest pattern.
  up.upscale(edges);
  up.upscale(flat);
  PatternNetworks patterns(*h.network, h.pool);
  const int64_t expected = (patterns.cost(0, 6, 5).macs + patterns.cost(narrowest, 6, 5).macs) / 2;
  EXPECT_NEAR(static_cast<double>(up.cost(6, 5)->macs - h.samplers->macs()), static_cast<double>(expected), 1.0);
  EXPECT_EQ(up.usage(), (std::vector<int64_t>{1, 0, 1}));
}

// In int8 every pattern runs quantized, calibrated on its own graph; the choice is the float32
// one's, and the output stays near float32's.
TEST(HybridModel, PatternsRunInInt8EachCalibratedOnItsOwnGraph) {
  torch::manual_seed(23);
  const HybridModel h = make_hybrid();
  PatternCalibration calibration;
  const graph::Graph g = h.network->describe();
  for (int i = 0; i < 4; ++i) {
    const Batch f = frame(10 + i);
    calibration.frames.push_back(network_inputs(g, f.lr_color, h.network->info_input(f)));
  }
  HybridUpscaler fp32("h", h), int8("h int8", h, Precision::Int8, calibration);
  EXPECT_EQ(int8.precision(), Precision::Int8);
  EXPECT_EQ(fp32.precision(), Precision::Fp32);
  for (int i = 0; i < 3; ++i) {
    const Batch f = frame(20 + i);
    const auto reference = fp32.upscale(f), quantized = int8.upscale(f);
    EXPECT_EQ(int8.frame_choice()->pattern, fp32.frame_choice()->pattern);
    ASSERT_TRUE(torch::isfinite(quantized).all().item<bool>());
    EXPECT_FALSE(torch::equal(quantized, reference));  // it did run quantized
    const double mse = (quantized - reference).square().mean().item<double>();
    const double peak = reference.abs().max().item<double>();
    EXPECT_GT(10 * std::log10(peak * peak / mse), 25.0);
  }
  // Without calibration frames an int8 hybrid cannot be built.
  EXPECT_THROW(HybridUpscaler("h int8", h, Precision::Int8), Error);
}
