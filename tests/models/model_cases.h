#pragma once
// Shared fixtures of the models tests: every backbone at every scale, and small inputs.

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <string>
#include <vector>

#include "models/arch_spec.h"
#include "models/backbone_registry.h"
#include "models/sr_network.h"

namespace cgsr::test {

struct BackboneCase {
  std::string backbone;
  int scale;
  std::string colors;
};

// Every registered backbone at every scale, and in Y where it supports luma: a backbone added to
// models/backbones/ is checked by every test that loops over these as soon as its file exists.
inline std::vector<BackboneCase> all_backbone_cases() {
  std::vector<BackboneCase> cases;
  const auto& registry = backbone_registry();
  for (const auto& b : registry.names())
    for (int s : {2, 3, 4}) cases.push_back({b, s, "rgb"});
  for (const auto& b : registry.names())
    if (registry.get(b).supports_y)
      for (int s : {2, 3, 4}) cases.push_back({b, s, "y"});
  return cases;
}

inline ArchSpec spec_for(const BackboneCase& c) {
  ArchSpec s = default_spec(c.backbone, c.scale);
  s.colors = enum_from_name<Colors>(c.colors);
  return resolve_spec(s);
}

inline std::string case_name(const BackboneCase& c) {
  return c.backbone + " x" + std::to_string(c.scale) + (c.colors == "y" ? " (Y)" : "");
}

// Whether the backbone has HR features for the RIT's HR branch and the geometry head (SPAN has not).
inline bool has_hr_features(const std::string& backbone) { return backbone_registry().get(backbone).has_hr_features; }
// The RIT sources the backbone takes.
inline std::vector<std::string> rit_sources_for(const std::string& backbone) {
  std::vector<std::string> sources;
  for (const auto& source : rit_sources())
    if (has_hr_features(backbone) || source.find("hr_fuse") == std::string::npos) sources.push_back(source);
  return sources;
}

// A spec with a RIT reading every channel the paper uses.
inline ArchSpec with_rit(ArchSpec s, const std::string& source = "lr", const std::string& fusion = "concat",
                         bool geometry = false) {
  s.rit.enabled = true;
  s.rit.source = enum_from_name<RitSource>(source);
  s.rit.fusion = enum_from_name<RitFusion>(fusion);
  s.geometry.enabled = geometry;
  return resolve_spec(s);
}

// Random colour and rendering information for a spec, LR size w x h.
inline std::pair<torch::Tensor, torch::Tensor> random_inputs(const ArchSpec& s, int64_t w, int64_t h, int64_t n = 1) {
  const auto color = torch::rand({n, 3, h, w});
  torch::Tensor info;
  if (s.rit.enabled) {
    const int64_t f = s.rit.reads_hr() ? s.scale : 1;
    info = torch::rand({n, static_cast<int64_t>(s.rit.info_width()), h * f, w * f});
  }
  return {color, info};
}

// A fresh RIT fuses with zero convs (it starts as the plain backbone); random fusion weights make
// the rendering information change the output.
inline void randomize_fusion(SRNetworkImpl& net, double stddev = 0.05) {
  torch::NoGradGuard no_grad;
  for (auto* fuse : {&net.rit()->fuse, &net.rit()->hr_fuse}) {
    if (fuse->is_empty()) continue;
    (*fuse)->weight.normal_(0, stddev);
    (*fuse)->bias.normal_(0, stddev / 5);
  }
}

// Random gate and fusion weights make a wrong RIT export visible in the outputs.
inline SRNetwork build_network(const ArchSpec& spec, uint64_t seed) {
  torch::manual_seed(seed);
  SRNetwork net(spec);
  if (net->has_rit()) {
    torch::NoGradGuard no_grad;
    net->rit()->gate.uniform_(0.5, 1.5);
    randomize_fusion(*net);
  }
  net->eval();
  return net;
}

// The graph contract (models/graph.h): interpreting the network's training graph reproduces
// forward_train() bit for bit, the geometry head's output too.
inline void expect_graph_matches_forward(const ArchSpec& spec) {
  SRNetwork net(spec);
  if (net->has_rit()) randomize_fusion(*net, 0.1);  // so the RIT path is exercised
  const auto [color, info] = random_inputs(spec, 7, 5);
  torch::NoGradGuard no_grad;
  const auto expected = net->forward_train(color, info);
  const auto g = net->describe(/*training=*/true);
  const auto outputs = graph::run(g, network_inputs(g, color, info));
  ASSERT_GE(outputs.size(), 1u);
  EXPECT_EQ(outputs[0].first, "image");
  EXPECT_TRUE(torch::equal(outputs[0].second, expected.image));
  if (spec.geometry.enabled) {
    ASSERT_EQ(outputs.size(), 2u);
    EXPECT_TRUE(torch::equal(outputs[1].second, expected.geometry));
  }
}

}  // namespace cgsr::test
