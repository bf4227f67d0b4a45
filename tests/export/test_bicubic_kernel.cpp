// The conv form of bicubic upsampling written into ONNX files equals our bicubic resize.

#include <gtest/gtest.h>

#include <torch/torch.h>

#include "export/bicubic_kernel.h"
#include "models/graph.h"

namespace cgsr {
namespace {

TEST(BicubicKernel, PhaseTapsSumToOneAndSpanFiveOffsets) {
  for (int64_t f : {2, 3, 4})
    for (int64_t p = 0; p < f; ++p) {
      const auto taps = bicubic_phase_taps(f, p);
      ASSERT_EQ(taps.numel(), 5);
      EXPECT_NEAR(taps.sum().item<double>(), 1.0, 1e-12) << "factor " << f << " phase " << p;
      // Exactly one of the outer taps is unused: the four taps sit left or right of the centre.
      EXPECT_TRUE(taps[0].item<double>() == 0.0 || taps[4].item<double>() == 0.0);
    }
}

TEST(BicubicKernel, EdgePadPhaseConvAndDepthToSpaceEqualTheBicubicResize) {
  torch::manual_seed(7);
  for (int64_t f : {2, 3, 4}) {
    const int64_t c = 3;
    const auto x = torch::rand({2, c, 7, 9});
    const auto kernels = bicubic_phase_kernels(f).repeat({c, 1, 1, 1});
    const auto padded = torch::replication_pad2d(x, {2, 2, 2, 2});
    const auto phases = torch::conv2d(padded, kernels, torch::Tensor(), torch::IntArrayRef{1, 1}, torch::IntArrayRef{0, 0},
                                        torch::IntArrayRef{1, 1}, c);
    const auto got = torch::pixel_shuffle(phases, f);
    const auto want = graph::apply_resize(x, f, graph::ResizeMode::Bicubic);
    ASSERT_EQ(got.sizes(), want.sizes());
    EXPECT_LT((got - want).abs().max().item<double>(), 2e-6) << "factor " << f;
  }
}

}  // namespace
}  // namespace cgsr
