// Network-level numerical stability (issue 19): every backbone, plain and with a RIT from every
// source, gives finite outputs in both inference engines on extreme colours, frames smaller than
// a kernel and extreme rendering information; invalid inputs are clear errors or propagate locally.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <array>
#include <functional>
#include <limits>
#include <tuple>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/tensor_checks.h"
#include "models/arch_spec.h"
#include "models/fused_graph.h"
#include "models/rit.h"
#include "models/sr_network.h"
#include "render_data/render_channels.h"
#include "tests/models/model_cases.h"

using namespace cgsr;
using namespace cgsr::test;

namespace {

// A small network: two blocks (SRCNN has none), plain or with a RIT reading every channel the
// paper uses (depth 1, normal 3, normal_angle 1, edge 1) from `source`.
ArchSpec small_spec(const std::string& backbone, const std::string& source, int scale = 2) {
  std::string yaml = "backbone: " + backbone + "\nscale: " + std::to_string(scale) + "\n";
  if (backbone != "srcnn") yaml += "blocks: 2\n";
  if (!source.empty())
    yaml += "rit: {enabled: true, channels: [depth, normal, normal_angle, edge], source: " + source + "}\n";
  return spec_from_yaml(yaml, "test");
}

struct NetworkCase {
  std::string backbone, source;  // source "" = no RIT
  std::string name() const { return backbone + (source.empty() ? " plain" : " + RIT " + source); }
};

std::vector<NetworkCase> all_network_cases() {
  std::vector<NetworkCase> cases;
  for (const char* backbone : {"srcnn", "edsr", "pan"}) {
    cases.push_back({backbone, ""});
    for (const auto& source : rit_sources()) cases.push_back({backbone, source});
  }
  return cases;
}

// A network moved away from its initialization: every weight scaled by a random factor in
// [0.5, 1.5], random RIT gates, and random fusion convolutions (they start at zero, and a zero
// fusion would leave the RIT path untested).
SRNetwork perturbed_network(const ArchSpec& spec, uint64_t seed) {
  torch::manual_seed(seed);
  SRNetwork net(spec);
  {
    torch::NoGradGuard no_grad;
    for (auto& p : net->parameters()) p.mul_(torch::empty_like(p).uniform_(0.5, 1.5));
    if (net->has_rit()) {
      net->rit()->gate.uniform_(0.5, 1.5);
      randomize_fusion(*net, 0.1);
    }
  }
  net->eval();
  return net;
}

// One network in both inference engines: the modules' forward (LibTorch) and the fused oneDNN
// graph, a snapshot of the same weights.
struct Engines {
  explicit Engines(const ArchSpec& spec, uint64_t seed)
      : net(perturbed_network(spec, seed)), fused(net->describe()) {}

  // Rendering information the network reads for LR colour [n, 3, h, w]: at LR for `lr`, at HR
  // for every other source; each value from `make` ([n, C, H, W] -> tensor).
  torch::Tensor info_for(const torch::Tensor& color, const std::function<torch::Tensor(std::vector<int64_t>)>& make) const {
    if (!net->has_rit()) return {};
    const int64_t f = net->rit()->info_factor();
    return make({color.size(0), net->spec().rit.info_width(), color.size(2) * f, color.size(3) * f});
  }

  // Runs both engines; expects the right shape, finite values and agreement up to rounding.
  // Returns the LibTorch output.
  torch::Tensor expect_finite(const torch::Tensor& color, const torch::Tensor& info, const std::string& what) {
    torch::NoGradGuard no_grad;
    const int64_t s = net->spec().scale;
    const std::vector<int64_t> shape = {color.size(0), 3, color.size(2) * s, color.size(3) * s};
    const auto reference = net->forward(color, info);
    const auto fast = fused.run(color, info);
    EXPECT_EQ(reference.sizes().vec(), shape) << what;
    EXPECT_EQ(fast.sizes().vec(), shape) << what;
    EXPECT_TRUE(torch::isfinite(reference).all().item<bool>()) << what << ": libtorch engine";
    EXPECT_TRUE(torch::isfinite(fast).all().item<bool>()) << what << ": fused engine";
    if (reference.sizes() == fast.sizes()) {
      const double magnitude = std::max(1.0, reference.abs().max().item<double>());
      EXPECT_LE((reference - fast).abs().max().item<double>(), 1e-3 * magnitude) << what << ": engines differ";
    }
    return reference;
  }

  SRNetwork net;
  FusedGraph fused;
};

torch::Tensor constant_color(int64_t h, int64_t w, float r, float g, float b) {
  return torch::tensor({r, g, b}).view({1, 3, 1, 1}).expand({1, 3, h, w}).contiguous();
}

// Rendering information with every channel set per pixel by the caller: depth [1, 1, H, W]
// (already encoded), a normal (x, y, z), normal_angle and edge.
torch::Tensor make_info(const torch::Tensor& depth, std::array<float, 3> normal, float angle, float edge) {
  const int64_t h = depth.size(2), w = depth.size(3);
  const auto n = torch::tensor({normal[0], normal[1], normal[2]}).view({1, 3, 1, 1}).expand({1, 3, h, w});
  return torch::cat({depth, n, torch::full({1, 1, h, w}, angle), torch::full({1, 1, h, w}, edge)}, 1).contiguous();
}

}  // namespace

TEST(NetworkNumerics, ExtremeColoursGiveFiniteOutputsForEveryNetwork) {
  const int64_t h = 5, w = 7;
  const auto checker = (torch::arange(h).view({h, 1}) + torch::arange(w).view({1, w})).remainder(2).to(torch::kFloat);
  const std::vector<std::pair<std::string, torch::Tensor>> colours = {
      {"black", constant_color(h, w, 0, 0, 0)},
      {"white", constant_color(h, w, 1, 1, 1)},
      {"red", constant_color(h, w, 1, 0, 0)},
      {"green", constant_color(h, w, 0, 1, 0)},
      {"blue", constant_color(h, w, 0, 0, 1)},
      {"1.5 everywhere", constant_color(h, w, 1.5f, 1.5f, 1.5f)},
      {"-0.5 everywhere", constant_color(h, w, -0.5f, -0.5f, -0.5f)},
      {"-0.5/1.5 checkerboard", (checker * 2 - 0.5f).expand({1, 3, h, w}).contiguous()},
  };
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
      for (int64_t side : {1, 2, 3}) {
        const auto color = torch::rand({1, 3, side, side});
        const auto info = e.info_for(color, [](std::vector<int64_t> s) { return torch::rand(s); });
        e.expect_finite(color, info, std::to_string(side) + "x" + std::to_string(side));
      }
      // Not square, and two items.
      const auto color = torch::rand({2, 3, 1, 3});
      e.expect_finite(color, e.info_for(color, [](std::vector<int64_t> s) { return torch::rand(s); }), "2 x 3x1");
    }
}

// Depth from 0 (before the near plane) to +inf (sky) with near 1e-3 and far 1e6 in every
// encoding; normals of zero length or all one way; every pixel an edge.
TEST(NetworkNumerics, ExtremeRenderingInformationGivesFiniteOutputsForEveryRitSource) {
  const double near = 1e-3, far = 1e6;
  const int64_t h = 4, w = 5;
  const float inf = std::numeric_limits<float>::infinity();
  // One linear depth per pixel, repeated: before, at and just after the near plane, mid-range,
  // at and beyond the far plane, sky.
  const auto linear = torch::tensor({0.f, 1e-4f, 1e-3f, 1.001e-3f, 1.f, 1e3f, 1e6f, 1e7f, inf});
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
      const int64_t pixels = h * f * w * f;
      const auto tiled = linear.repeat({(pixels + linear.numel() - 1) / linear.numel()}).slice(0, 0, pixels);
      const auto mixed = encode_depth(tiled.view({1, 1, h * f, w * f}), near, far, encoding);
      // The data side's promise the networks rely on: encoded depth is finite and in [0, 1].
      ASSERT_TRUE(torch::isfinite(mixed).all().item<bool>());
      EXPECT_GE(mixed.min().item<float>(), 0.f);
      EXPECT_LE(mixed.max().item<float>(), 1.f);
      const auto sky = encode_depth(torch::full({1, 1, h * f, w * f}, inf), near, far, encoding);
      const auto at_near = encode_depth(torch::full({1, 1, h * f, w * f}, near), near, far, encoding);
      EXPECT_EQ(sky.min().item<float>(), 1.f);
      EXPECT_LE(at_near.max().item<float>(), 1e-6f);  // 0 up to rounding (linear: near / far)

      e.expect_finite(color, make_info(mixed, {0, 0, 0}, 1, 1), "mixed depth, zero-length normals, all edges");
      e.expect_finite(color, make_info(sky, {0, 0, 0}, 0, 0), "all sky");
      const auto far_away =
          e.expect_finite(color, make_info(sky, {0, 0, 1}, 1, 1), "all sky, all edges, normals towards the camera");
      const auto close_up =
          e.expect_finite(color, make_info(at_near, {1, 0, 0}, 1, 1), "all at the near plane, normals to the right");
      EXPECT_GT((far_away - close_up).abs().max().item<double>(), 1e-4) << "the RIT does not reach the output";
      e.expect_finite(color, make_info(at_near, {0, -1, 0}, 0, 1), "all at the near plane, normals down");
      e.expect_finite(torch::zeros_like(color), make_info(mixed, {0, 0, -1}, 1, 1), "black, mixed depth");
      e.expect_finite(torch::ones_like(color), make_info(sky, {0, 0, 0}, 1, 1), "white, sky");
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
