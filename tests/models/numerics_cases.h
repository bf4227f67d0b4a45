#pragma once
// Fixtures of the network-level numerics tests (issue 19): every backbone plain and with a RIT
// from every source, moved away from its initialization, run in both inference engines, and the
// extreme inputs built from constant colours and per-pixel rendering information. The LibTorch,
// fused and exported-ONNX numerics tests share them.

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <algorithm>
#include <array>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "models/arch_spec.h"
#include "models/fused_graph.h"
#include "models/rit.h"
#include "models/sr_network.h"
#include "render_data/render_channels.h"
#include "tests/models/model_cases.h"

namespace cgsr::test {

// A small network: two blocks (SRCNN has none), plain or with a RIT reading every channel the
// paper uses (depth 1, normal 3, normal_angle 1, edge 1) from `source`.
inline ArchSpec small_spec(const std::string& backbone, const std::string& source, int scale = 2) {
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

inline std::vector<NetworkCase> all_network_cases() {
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
inline SRNetwork perturbed_network(const ArchSpec& spec, uint64_t seed) {
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

inline torch::Tensor constant_color(int64_t h, int64_t w, float r, float g, float b) {
  return torch::tensor({r, g, b}).view({1, 3, 1, 1}).expand({1, 3, h, w}).contiguous();
}

// Rendering information with every channel set per pixel by the caller: depth [1, 1, H, W]
// (already encoded), a normal (x, y, z), normal_angle and edge.
inline torch::Tensor make_info(const torch::Tensor& depth, std::array<float, 3> normal, float angle, float edge) {
  const int64_t h = depth.size(2), w = depth.size(3);
  const auto n = torch::tensor({normal[0], normal[1], normal[2]}).view({1, 3, 1, 1}).expand({1, 3, h, w});
  return torch::cat({depth, n, torch::full({1, 1, h, w}, angle), torch::full({1, 1, h, w}, edge)}, 1).contiguous();
}

// Black, white, saturated and out-of-range colours, LR size w x h.
inline std::vector<std::pair<std::string, torch::Tensor>> extreme_colours(int64_t h, int64_t w) {
  const auto checker = (torch::arange(h).view({h, 1}) + torch::arange(w).view({1, w})).remainder(2).to(torch::kFloat);
  return {
      {"black", constant_color(h, w, 0, 0, 0)},
      {"white", constant_color(h, w, 1, 1, 1)},
      {"red", constant_color(h, w, 1, 0, 0)},
      {"green", constant_color(h, w, 0, 1, 0)},
      {"blue", constant_color(h, w, 0, 0, 1)},
      {"1.5 everywhere", constant_color(h, w, 1.5f, 1.5f, 1.5f)},
      {"-0.5 everywhere", constant_color(h, w, -0.5f, -0.5f, -0.5f)},
      {"-0.5/1.5 checkerboard", (checker * 2 - 0.5f).expand({1, 3, h, w}).contiguous()},
  };
}

// LR colour shapes below a 3x3 kernel's reach: 1x1, 2x2, 3x3, and a 3x1 frame of two items.
inline std::vector<std::vector<int64_t>> small_frame_shapes() {
  return {{1, 3, 1, 1}, {1, 3, 2, 2}, {1, 3, 3, 3}, {2, 3, 1, 3}};
}

// Encoded depth planes [1, 1, h, w] with near 1e-3 and far 1e6: `mixed` tiles one linear depth per
// pixel (before, at and just after the near plane, mid-range, at and beyond the far plane, sky),
// `sky` is +inf everywhere (an all-sky frame, no geometry), `at_near` the near plane everywhere.
struct ExtremeDepths {
  static constexpr double kNear = 1e-3, kFar = 1e6;
  torch::Tensor mixed, sky, at_near;
};

inline ExtremeDepths extreme_depths(int64_t h, int64_t w, DepthEncoding encoding) {
  const float inf = std::numeric_limits<float>::infinity();
  const auto linear = torch::tensor({0.f, 1e-4f, 1e-3f, 1.001e-3f, 1.f, 1e3f, 1e6f, 1e7f, inf});
  const int64_t pixels = h * w;
  const auto tiled = linear.repeat({(pixels + linear.numel() - 1) / linear.numel()}).slice(0, 0, pixels);
  const auto encode = [&](const torch::Tensor& linear_depth) {
    return encode_depth(linear_depth, ExtremeDepths::kNear, ExtremeDepths::kFar, encoding);
  };
  return {encode(tiled.view({1, 1, h, w})), encode(torch::full({1, 1, h, w}, inf)),
          encode(torch::full({1, 1, h, w}, ExtremeDepths::kNear))};
}

struct InputCase {
  std::string name;
  torch::Tensor color, info;
};

// Extreme rendering information for LR colour `color` (depth planes at the information's size):
// normals of zero length or all one way, every pixel an edge or none, all sky or all at the near
// plane. Names are unique; kFarAway and kCloseUp must differ when the RIT reaches the output.
inline constexpr const char* kFarAway = "all sky, all edges, normals towards the camera";
inline constexpr const char* kCloseUp = "all at the near plane, normals to the right";
inline std::vector<InputCase> extreme_information(const torch::Tensor& color, const ExtremeDepths& d) {
  return {
      {"mixed depth, zero-length normals, all edges", color, make_info(d.mixed, {0, 0, 0}, 1, 1)},
      {"all sky", color, make_info(d.sky, {0, 0, 0}, 0, 0)},
      {kFarAway, color, make_info(d.sky, {0, 0, 1}, 1, 1)},
      {kCloseUp, color, make_info(d.at_near, {1, 0, 0}, 1, 1)},
      {"all at the near plane, normals down", color, make_info(d.at_near, {0, -1, 0}, 0, 1)},
      {"black, mixed depth", torch::zeros_like(color), make_info(d.mixed, {0, 0, -1}, 1, 1)},
      {"white, sky", torch::ones_like(color), make_info(d.sky, {0, 0, 0}, 1, 1)},
  };
}

}  // namespace cgsr::test
