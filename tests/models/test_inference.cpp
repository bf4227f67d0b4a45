// The inference helper: eval mode, no autograd, identical results in both memory layouts.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

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
  EXPECT_EQ(enum_from_name<MemoryLayout>("nhwc"), MemoryLayout::Nhwc);
  EXPECT_EQ(enum_name(MemoryLayout::Auto), "auto");
  EXPECT_THROW(enum_from_name<MemoryLayout>("chw"), Error);
}

TEST(MemoryLayout, ParametersChangeLayoutInPlaceAndKeepValues) {
  torch::manual_seed(4);
  SRNetwork net(default_spec("pan", 2));
  const auto before = net->parameters();
  std::vector<torch::Tensor> values;
  for (const auto& p : before) values.push_back(p.detach().clone());
  set_parameter_layout(*net, MemoryLayout::Nhwc);
  const auto after = net->parameters();
  for (size_t i = 0; i < after.size(); ++i) {
    EXPECT_TRUE(after[i].is_same(before[i])) << i;  // the same tensors: optimizers stay valid
    EXPECT_TRUE(torch::equal(after[i], values[i])) << i;
    if (after[i].dim() == 4) {
      EXPECT_TRUE(after[i].is_contiguous(torch::MemoryFormat::ChannelsLast)) << i;
    }
  }
  set_parameter_layout(*net, MemoryLayout::Nchw);
  for (const auto& p : net->parameters()) EXPECT_TRUE(p.is_contiguous());
}

TEST(MemoryLayout, MeasuredChoiceIsRememberedPerKey) {
  int calls = 0;
  const auto run = [&](MemoryLayout layout) {
    ++calls;
    // NCHW made slow on purpose: the measurement must pick NHWC.
    if (layout == MemoryLayout::Nchw) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  };
  EXPECT_EQ(measured_layout("test key", run, 3), MemoryLayout::Nhwc);
  EXPECT_EQ(calls, 8);  // one warm-up and three rounds of each
  EXPECT_EQ(measured_layout("test key", run, 3), MemoryLayout::Nhwc);
  EXPECT_EQ(calls, 8);
}

TEST(Inference, AutoLayoutGivesTheReferenceOutput) {
  torch::manual_seed(5);
  SRNetwork net(default_spec("pan", 2));
  const auto color = torch::rand({1, 3, 9, 11});
  const MemoryLayout chosen = inference_layout(*net, color, {});
  EXPECT_NE(chosen, MemoryLayout::Auto);
  torch::NoGradGuard no_grad;
  EXPECT_TRUE(torch::allclose(infer(*net, color), net->forward(color), 1e-4, 1e-5));
}
