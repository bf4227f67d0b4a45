// Network-level numerical stability (issue 19), through NetworkUpscaler: both inference engines
// give finite outputs on extreme frames and, as Upscaler::upscale() documents, do not clamp them
// (evaluation clamps), so the output is the network's own in either engine.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include "eval/upscaler.h"
#include "models/arch_spec.h"
#include "models/inference.h"
#include "tests/models/model_cases.h"

using namespace cgsr;
using namespace cgsr::test;

TEST(NetworkNumerics, UpscalerOutputIsFiniteAndUnclampedInBothEngines) {
  const std::vector<std::string> specs = {
      "backbone: pan\nscale: 2\nblocks: 2\nrit: {enabled: true, source: lr}\n",
      "backbone: edsr\nscale: 2\nblocks: 2\nrit: {enabled: true, source: hr_unshuffle+hr_fuse}\n",
      "backbone: srcnn\nscale: 2\n",
  };
  const int64_t h = 6, w = 5;
  uint64_t seed = 2300;
  bool outside_unit_range = false;
  for (const auto& yaml : specs) {
    SRNetwork net = build_network(spec_from_yaml(yaml, "test"), ++seed);
    SCOPED_TRACE(spec_summary(net->spec()));
    NetworkUpscaler fused("fused", net, InferenceEngine::Fused), libtorch("libtorch", net, InferenceEngine::LibTorch);
    for (float value : {0.f, 1.f, 1.5f, -0.5f}) {
      SCOPED_TRACE(value);
      Batch batch;
      batch.scale = 2;
      batch.channels = parse_channels({"depth", "normal", "normal_angle", "edge"});
      batch.depth_encoding = DepthEncoding::Log;
      batch.lr_color = torch::full({1, 3, h, w}, value);
      batch.lr_info = torch::rand({1, 6, h, w});
      batch.hr_info = torch::rand({1, 6, 2 * h, 2 * w});
      torch::Tensor expected;
      {
        torch::NoGradGuard no_grad;
        expected = net->forward(batch.lr_color, net->info_input(batch));
      }
      for (Upscaler* upscaler : {static_cast<Upscaler*>(&fused), static_cast<Upscaler*>(&libtorch)}) {
        SCOPED_TRACE(upscaler->name());
        const auto out = upscaler->upscale(batch);
        ASSERT_EQ(out.sizes().vec(), (std::vector<int64_t>{1, 3, 2 * h, 2 * w}));
        EXPECT_TRUE(torch::isfinite(out).all().item<bool>());
        EXPECT_FALSE(out.requires_grad());
        EXPECT_LE((out - expected).abs().max().item<double>(), 1e-4 * std::max(1.0, expected.abs().max().item<double>()));
        outside_unit_range |= out.min().item<float>() < 0.f || out.max().item<float>() > 1.f;
      }
    }
  }
  // So the comparison above shows the output is not clamped.
  EXPECT_TRUE(outside_unit_range);
}
