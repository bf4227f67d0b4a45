// Hybrid model files: the static network loads as a plain model, the dynamic pruning components
// round-trip exactly, and the upscaler chooses per frame from current and previous information.
#include <gtest/gtest.h>

#include "core/error.h"
#include "pruning/hybrid_model.h"
#include "pruning/hybrid_upscaler.h"
#include "pruning/pattern_executor.h"
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
  const auto units = find_units(net->describe(false));
  const PatternPool pool = random_pool(units, 3, 0.5, 7);
  std::vector<std::vector<int64_t>> counts;
  for (const auto& u : pool.units) counts.push_back({3, 0, 1});
  StaticPruneOptions options;
  options.rit_threshold = 0;
  StaticPruning pruned = static_prune(*net, pool, counts, options);
  SamplerOptions so;
  so.channels = {"depth", "edge"};
  so.grid = 4;
  so.width = 3;
  HybridModel h;
  h.samplers = DynamicSamplers(so, std::vector<int>(units.size(), 3));
  h.samplers->keep_patterns(pruned.kept);
  h.network = pruned.network;
  h.pool = pruned.pool;
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
  HybridUpscaler a("a", h), b("b", loaded);
  EXPECT_EQ(b.channels(), parse_channels({"depth", "normal_angle", "edge"}));
  for (int i = 0; i < 3; ++i) {
    const Batch f = frame(i);
    EXPECT_TRUE(torch::equal(a.upscale(f), b.upscale(f)));
    EXPECT_EQ(a.frame_details()["patterns"], b.frame_details()["patterns"]);
  }
  // The output is the chosen patterns' execution on the static network.
  const Batch f = frame(7);
  const auto out = b.upscale(f);
  std::vector<int> choice;
  const auto details = b.frame_details();  // a copy: iterating a temporary's items() would dangle
  for (const auto& [unit, k] : details["patterns"].items()) choice.push_back(k.get<int>());
  PatternExecutor exec(*loaded.network, loaded.pool);
  EXPECT_TRUE(torch::allclose(out, exec.run(f.lr_color, f.lr_info, choice), 0, 1e-6));
  EXPECT_GE(b.frame_details()["choose_ms"].get<double>(), 0.0);

  save_model(dir / "plain.cgsr", *h.network);
  EXPECT_THROW(load_hybrid_model(dir / "plain.cgsr"), Error);
  std::filesystem::remove_all(dir);
}

TEST(HybridModel, UsesThePreviousFrame) {
  torch::manual_seed(17);
  HybridUpscaler up("h", make_hybrid());
  const Batch f0 = frame(4), f1 = frame(5);
  up.upscale(f1);
  EXPECT_FALSE(up.frame_details()["previous_frame"].get<bool>());
  up.previous_frame(f0);
  up.upscale(f1);
  EXPECT_TRUE(up.frame_details()["previous_frame"].get<bool>());
  // Frame after frame, the last upscaled frame is the previous one.
  up.upscale(f0);
  up.upscale(f1);
  EXPECT_TRUE(up.frame_details()["previous_frame"].get<bool>());
  Batch two = frame(6);  // patterns are chosen per frame: one frame at a time
  two.lr_color = torch::rand({2, 3, 5, 6});
  two.lr_info = torch::rand({2, 3, 5, 6});
  EXPECT_THROW(up.upscale(two), Error);
  const auto cost = up.cost(6, 5);
  ASSERT_TRUE(cost.has_value());
  EXPECT_GT(cost->macs, 0);
}
