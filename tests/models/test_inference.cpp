// The inference helper: eval mode, no autograd, identical results in both memory layouts.
#include <gtest/gtest.h>

#include "core/error.h"
#include "models/inference.h"
#include "tests/models/model_cases.h"

using namespace cgsr;
using namespace cgsr::test;

TEST(Inference, MatchesForwardWithoutAutograd) {
  torch::manual_seed(12);
  for (const char* b : {"srcnn", "edsr", "pan"}) {
    SCOPED_TRACE(b);
    const ArchSpec spec = with_rit(default_spec(b, 2));
    SRNetwork net(spec);
    const auto [color, info] = random_inputs(spec, 6, 5);
    const auto out = infer(*net, color, info);
    EXPECT_FALSE(out.requires_grad());
    EXPECT_FALSE(net->is_training());
    EXPECT_TRUE(out.is_contiguous());
    torch::NoGradGuard no_grad;
    const auto ref = net->forward(color, info);
    EXPECT_TRUE(torch::allclose(out, ref, 1e-5, 1e-5));
    const auto nchw = infer(*net, color, info, MemoryLayout::Nchw);
    const auto nhwc = infer(*net, color, info, MemoryLayout::Nhwc);
    EXPECT_TRUE(torch::equal(nchw, ref));
    EXPECT_TRUE(nhwc.is_contiguous());
    EXPECT_TRUE(torch::allclose(nhwc, ref, 1e-4, 1e-5));
  }
}

TEST(Inference, LayoutNames) {
  EXPECT_EQ(memory_layout_from_name("nhwc"), MemoryLayout::Nhwc);
  EXPECT_STREQ(memory_layout_name(MemoryLayout::Auto), "auto");
  EXPECT_THROW(memory_layout_from_name("chw"), Error);
}
