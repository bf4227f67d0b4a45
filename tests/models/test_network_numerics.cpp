// Network-level numerical stability (issue 19): every backbone, plain and with a RIT from every
// source, gives finite outputs in both inference engines on extreme colours, frames smaller than
// a kernel and extreme rendering information; invalid inputs are clear errors or propagate locally.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <limits>
#include <map>
#include <tuple>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/tensor_checks.h"
#include "models/arch_spec.h"
#include "render_data/render_channels.h"
#include "tests/models/numerics_cases.h"

using namespace cgsr;
using namespace cgsr::test;

TEST(NetworkNumerics, ExtremeColoursGiveFiniteOutputsForEveryNetwork) {
  const int64_t h = 5, w = 7;
  const auto colours = extreme_colours(h, w);
  uint64_t seed = 1900;
  int rit_networks = 0;
  for (const auto& c : all_network_cases()) {
    SCOPED_TRACE(c.name());
    Engines e(small_spec(c.backbone, c.source), ++seed);
    const auto info = e.info_for(colours[0].second, [](std::vector<int64_t> s) { return torch::rand(s); });
    for (const auto& [name, colour] : colours) e.expect_finite(colour, info, name);
    if (!info.defined()) continue;
    // The RIT path is live: other rendering information gives another output.
    ++rit_networks;
    const auto color = torch::rand({1, 3, h, w});
    const auto with = e.expect_finite(color, info, "random colour");
    const auto other = e.expect_finite(color, torch::rand_like(info), "random colour, other information");
    const double change = (with - other).abs().max().item<double>();
    EXPECT_GT(change, 1e-4) << "the rendering information does not reach the output";
  }
  EXPECT_EQ(rit_networks, 3 * static_cast<int>(rit_sources().size()));
}

TEST(NetworkNumerics, FramesSmallerThanAKernelGiveFiniteOutputsForEveryNetwork) {
  uint64_t seed = 1950;
  for (int scale : {2, 3, 4})
    for (const auto& c : all_network_cases()) {
      SCOPED_TRACE(c.name() + " x" + std::to_string(scale));
      Engines e(small_spec(c.backbone, c.source, scale), ++seed);
      for (const auto& shape : small_frame_shapes()) {
        const auto color = torch::rand(shape);
        const auto info = e.info_for(color, [](std::vector<int64_t> s) { return torch::rand(s); });
        e.expect_finite(color, info, shape_string(color));
      }
    }
}

// Depth from 0 (before the near plane) to +inf (sky) with near 1e-3 and far 1e6 in every
// encoding; normals of zero length or all one way; every pixel an edge.
TEST(NetworkNumerics, ExtremeRenderingInformationGivesFiniteOutputsForEveryRitSource) {
  const int64_t h = 4, w = 5;
  uint64_t seed = 2000;
  for (const auto& c : all_network_cases()) {
    if (c.source.empty()) continue;
    for (const auto& encoding_name : EnumNames<DepthEncoding>::names()) {
      const DepthEncoding encoding = enum_from_name<DepthEncoding>(encoding_name);
      SCOPED_TRACE(c.name() + ", " + encoding_name + " depth");
      ArchSpec spec = small_spec(c.backbone, c.source);
      spec.rit.depth_encoding = encoding;
      Engines e(resolve_spec(spec), ++seed);
      const auto color = torch::rand({1, 3, h, w});
      const int64_t f = e.net->rit()->info_factor();
      const ExtremeDepths d = extreme_depths(h * f, w * f, encoding);
      // The data side's promise the networks rely on: encoded depth is finite and in [0, 1].
      ASSERT_TRUE(torch::isfinite(d.mixed).all().item<bool>());
      EXPECT_GE(d.mixed.min().item<float>(), 0.f);
      EXPECT_LE(d.mixed.max().item<float>(), 1.f);
      EXPECT_EQ(d.sky.min().item<float>(), 1.f);
      EXPECT_LE(d.at_near.max().item<float>(), 1e-6f);  // 0 up to rounding (linear: near / far)

      std::map<std::string, torch::Tensor> outputs;
      for (const auto& input : extreme_information(color, d))
        outputs[input.name] = e.expect_finite(input.color, input.info, input.name);
      EXPECT_GT((outputs[kFarAway] - outputs[kCloseUp]).abs().max().item<double>(), 1e-4)
          << "the RIT does not reach the output";
    }
  }
}

// A 0x0 (or 0-wide, or 0-item) frame has nothing to upscale: both engines say so with a
// cgsr::Error that shows the shape.
TEST(NetworkNumerics, EmptyFramesAreClearErrorsInBothEngines) {
  uint64_t seed = 2100;
  for (const auto& c : all_network_cases()) {
    SCOPED_TRACE(c.name());
    Engines e(small_spec(c.backbone, c.source), ++seed);
    for (const auto& shape : {std::vector<int64_t>{1, 3, 0, 0}, {1, 3, 0, 4}, {1, 3, 4, 0}, {0, 3, 4, 4}}) {
      const auto color = torch::zeros(shape);
      const auto info = e.info_for(color, [](std::vector<int64_t> s) { return torch::zeros(s); });
      const std::string shown = shape_string(color);
      SCOPED_TRACE(shown);
      torch::NoGradGuard no_grad;
      try {
        e.net->forward(color, info);
        ADD_FAILURE() << "libtorch engine: no error";
      } catch (const Error& err) {
        EXPECT_NE(std::string(err.what()).find(shown), std::string::npos) << err.what();
      } catch (const std::exception& err) {
        ADD_FAILURE() << "libtorch engine: not a cgsr::Error: " << err.what();
      }
      try {
        e.fused.run(color, info);
        ADD_FAILURE() << "fused engine: no error";
      } catch (const Error& err) {
        EXPECT_NE(std::string(err.what()).find(shown), std::string::npos) << err.what();
      } catch (const std::exception& err) {
        ADD_FAILURE() << "fused engine: not a cgsr::Error: " << err.what();
      }
    }
  }
}

// The networks do not check values: data sets reject NaN and infinite values when frames are
// loaded (frame_files.cpp, glob_layout.cpp), and evaluation rejects a non-finite output. A NaN
// pixel of the colour or the rendering information stays local in both engines: output pixels
// whose receptive field does not hold it equal the clean output. The LibTorch engine carries it to
// the output; the fused engine need not (oneDNN's ReLU gives 0 for NaN, so a plain SRCNN, where
// every path passes a ReLU, returns finite values), so a finite fused output does not prove
// finite input.
TEST(NetworkNumerics, NanInTheInputStaysWithinItsReceptiveField) {
  using torch::indexing::Slice;
  uint64_t seed = 2200;
  const int64_t h = 24, w = 24;
  const auto far_corner = Slice(2 * h - 8, torch::indexing::None);  // 40+ HR pixels from the NaN
  for (const auto& c : all_network_cases()) {
    Engines e(small_spec(c.backbone, c.source), ++seed);
    const auto color = torch::rand({1, 3, h, w});
    const auto info = e.info_for(color, [](std::vector<int64_t> s) { return torch::rand(s); });
    torch::NoGradGuard no_grad;
    const auto clean_reference = e.net->forward(color, info), clean_fast = e.fused.run(color, info);
    for (const bool in_info : {false, true}) {
      if (in_info && !info.defined()) continue;
      SCOPED_TRACE(c.name() + (in_info ? ", NaN in the rendering information" : ", NaN in the colour"));
      auto poisoned_color = color.clone(), poisoned_info = info.defined() ? info.clone() : info;
      (in_info ? poisoned_info : poisoned_color).index_put_({0, 0, 0, 0}, std::numeric_limits<float>::quiet_NaN());
      const auto reference = e.net->forward(poisoned_color, poisoned_info);
      const auto fast = e.fused.run(poisoned_color, poisoned_info);
      EXPECT_TRUE(torch::isnan(reference.index({0, Slice(), 0, 0})).any().item<bool>())
          << "libtorch engine: the NaN does not reach the output";
      for (const auto& [engine, out, clean] :
           {std::tuple{"libtorch", reference, clean_reference}, std::tuple{"fused", fast, clean_fast}}) {
        const auto far = out.index({0, Slice(), far_corner, far_corner});
        EXPECT_TRUE(torch::isfinite(far).all().item<bool>()) << engine << " engine: the NaN spreads";
        EXPECT_TRUE(torch::allclose(far, clean.index({0, Slice(), far_corner, far_corner}), 1e-5, 1e-5))
            << engine << " engine";
      }
    }
  }
}
