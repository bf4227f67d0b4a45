#pragma once
// Shared fixtures of the pruning tests: small networks of every backbone (with and without a
// RIT, pixel-shuffle and attention groups included), random weights, random pattern pools, and
// what a pattern computes through the graph interpreter.

#include <torch/torch.h>

#include <algorithm>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "models/arch_spec.h"
#include "models/channel_selection.h"
#include "models/complexity.h"
#include "models/elastic.h"
#include "models/sr_network.h"
#include "models/subnet.h"
#include "pruning/pattern_pool.h"
#include "pruning/prunable_units.h"
#include "tests/support/elastic_options.h"

namespace cgsr::test {

struct NetCase {
  std::string name;
  ArchSpec spec;
};

// A backbone with `blocks` blocks and every layer group `width` wide (features `features`).
inline ArchSpec small_spec(const std::string& backbone, int scale, int blocks, int width, int features,
                           bool rit = false) {
  ArchSpec s = default_spec(backbone, scale);
  if (backbone != "srcnn") s.blocks = blocks;
  s.widths = GroupWidths();
  s = resolve_spec(s);
  GroupWidths w;
  for (const auto& [group, unused] : s.widths.entries()) w.set(group, group == "features" ? features : width);
  s.widths = w;
  if (rit) {
    s.rit.enabled = true;
    s.rit.channels = {"depth", "normal_angle", "edge"};
    s.rit.width = 5;
  }
  return resolve_spec(s);
}

inline std::vector<NetCase> net_cases() {
  return {{"pan x2", small_spec("pan", 2, 2, 6, 8)},
          {"pan x4 + rit", small_spec("pan", 4, 2, 6, 8, true)},
          {"edsr x4", small_spec("edsr", 4, 2, 6, 8)},
          {"edsr x3 + rit", small_spec("edsr", 3, 1, 5, 8, true)},
          {"srcnn x2", small_spec("srcnn", 2, 0, 7, 7)}};
}

// Every parameter random (the RIT fusion starts at zero otherwise).
inline void randomize(SRNetworkImpl& net) {
  torch::NoGradGuard no_grad;
  for (auto& p : net.parameters()) p.normal_(0, 0.2);
}

inline std::pair<torch::Tensor, torch::Tensor> inputs_for(const SRNetworkImpl& net, int64_t w, int64_t h,
                                                           int64_t n = 1) {
  const auto color = torch::rand({n, 3, h, w});
  torch::Tensor info;
  if (net.has_rit()) {
    const int64_t f = net.rit()->info_factor();
    info = torch::rand({n, static_cast<int64_t>(net.spec().rit.info_width()), h * f, w * f});
  }
  return {color, info};
}

// `k` random subnets of `net` (quantum 2, at least one block), widest (most MACs) first.
inline PatternPool random_pool(const SRNetworkImpl& net, int k, uint64_t seed) {
  const ElasticSpace space(net.spec(), test::elastic_options(2, 0.25, 1));
  std::mt19937_64 rng(seed);
  std::vector<std::pair<int64_t, SubnetConfig>> drawn;
  std::set<std::string> keys;
  while (static_cast<int>(drawn.size()) < k) {
    SubnetConfig sub = space.sample(rng);
    if (!keys.insert(subnet_key(sub)).second) continue;
    drawn.emplace_back(complexity(subnet_graph(net, sub), 16, 12).macs, sub);
  }
  std::stable_sort(drawn.begin(), drawn.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  PatternPool pool;
  pool.spec = net.spec();
  for (auto& [macs, sub] : drawn) pool.patterns.push_back(sub);
  return pool;
}

// What pattern k of `pool` computes on `net` (the graph interpreter).
inline torch::Tensor run_pattern(const SRNetworkImpl& net, const PatternPool& pool, int k, const torch::Tensor& color,
                                 const torch::Tensor& info) {
  torch::NoGradGuard no_grad;
  const graph::Graph g = subnet_graph(net, pool.patterns.at(k));
  return graph::run(g, network_inputs(g, color, info)).front().second;
}

// The reference of a channel selection: the dense network with every convolution's input columns
// of removed channels set to zero (a copy of the weights), run by the graph interpreter.
// Removing a channel of a pruning unit can only act through the convolutions reading it.
inline torch::Tensor masked_dense(const SRNetworkImpl& net, const ChannelSelection& keep, const torch::Tensor& color,
                                  const torch::Tensor& info) {
  torch::NoGradGuard no_grad;
  graph::Graph g = net.describe(false);
  for (auto& op : g.ops) {
    if (op.kind != graph::OpKind::Conv) continue;
    auto w = op.weight.clone();
    int64_t offset = 0;
    for (const auto& s : g.values[op.inputs[0]].layout) {
      const auto it = s.prunable ? keep.find(s.group) : keep.end();
      if (it != keep.end())
        for (int64_t c = 0; c < s.channels; ++c)
          if (!std::binary_search(it->second.begin(), it->second.end(), c))
            w.slice(1, offset + c * s.repeat, offset + (c + 1) * s.repeat).zero_();
      offset += s.channels * s.repeat;
    }
    op.weight = w;
  }
  return graph::run(g, network_inputs(g, color, info)).front().second;
}

inline double max_diff(const torch::Tensor& a, const torch::Tensor& b) {
  return (a - b).abs().max().item<double>();
}

}  // namespace cgsr::test
