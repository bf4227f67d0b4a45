#include "models/subnet.h"

#include <torch/torch.h>

#include <algorithm>
#include <numeric>
#include <set>

#include "core/error.h"
#include "core/text.h"
#include "models/backbone_registry.h"
#include "models/inherit.h"
#include "models/reparameterization.h"

namespace cgsr {

std::vector<std::pair<std::string, int64_t>> layer_groups(const ArchSpec& spec) {
  std::vector<std::pair<std::string, int64_t>> out;
  for (const auto& [group, width] : spec.widths.entries()) out.emplace_back(group, width);
  if (spec.rit.enabled) {
    if (spec.rit.feature_branch()) out.emplace_back("rit", spec.rit.width);
    if (spec.rit.hr_branch()) out.emplace_back("rit_hr", spec.rit.hr_width);
  }
  return out;
}

namespace {

bool kept_block(const SubnetConfig& sub, int block) {
  return std::binary_search(sub.blocks.begin(), sub.blocks.end(), block);
}

// Block index of an op named "backbone.blocks.<i>.rest", or -1.
int op_block(const std::string& name) {
  static const std::string prefix = "backbone.blocks.";
  if (name.rfind(prefix, 0) != 0) return -1;
  const size_t dot = name.find('.', prefix.size());
  if (dot == std::string::npos || dot == prefix.size() || dot - prefix.size() > 6) return -1;
  int index = 0;
  for (size_t i = prefix.size(); i < dot; ++i) {
    if (name[i] < '0' || name[i] > '9') return -1;
    index = index * 10 + (name[i] - '0');
  }
  return index;
}

}  // namespace

SubnetConfig full_subnet(const ArchSpec& spec) {
  SubnetConfig sub;
  sub.blocks.resize(std::max(spec.blocks, 0));
  std::iota(sub.blocks.begin(), sub.blocks.end(), 0);
  for (const auto& [group, width] : layer_groups(spec)) sub.widths[group] = width;
  return sub;
}

int64_t subnet_width(const SubnetConfig& sub, const std::string& group, int64_t full_width) {
  const auto it = sub.widths.find(group);
  return it == sub.widths.end() ? full_width : it->second;
}

std::string subnet_key(const SubnetConfig& sub) {
  std::string key = "b=";
  for (size_t i = 0; i < sub.blocks.size(); ++i) key += (i ? "," : "") + std::to_string(sub.blocks[i]);
  for (const auto& [group, width] : sub.widths) {
    const auto block = parse_block_group(group);
    if (block && !kept_block(sub, block->first)) continue;  // a skipped block's widths change nothing
    key += "|" + group + "=" + std::to_string(width);
  }
  if (sub.precision != Precision::Fp32) key += "|" + enum_name(sub.precision);
  return key;
}

nlohmann::ordered_json to_json(const SubnetConfig& sub) {
  nlohmann::ordered_json widths = nlohmann::ordered_json::object();
  for (const auto& [group, width] : sub.widths) widths[group] = width;
  nlohmann::ordered_json j = {{"blocks", sub.blocks}, {"widths", widths}};
  if (sub.precision != Precision::Fp32) j["precision"] = sub.precision;
  return j;
}

SubnetConfig subnet_from_json(const nlohmann::ordered_json& j, const std::string& context) {
  SubnetConfig sub;
  try {
    sub.blocks = j.at("blocks").get<std::vector<int>>();
    const auto& widths = j.at("widths");
    if (!widths.is_object()) throw Error(context + ": widths", "expected a map of layer group -> channels");
    for (const auto& [group, width] : widths.items()) sub.widths[group] = width.get<int64_t>();
    if (j.contains("precision")) sub.precision = j.at("precision").get<Precision>();
  } catch (const nlohmann::json::exception& e) {
    throw Error(context, std::string("malformed subnet: ") + e.what());
  }
  return sub;
}

std::vector<std::string> subnet_problems(const ArchSpec& spec, const SubnetConfig& sub) {
  std::vector<std::string> p;
  for (size_t i = 0; i < sub.blocks.size(); ++i) {
    const int b = sub.blocks[i];
    if (b < 0 || b >= spec.blocks) p.push_back("block " + std::to_string(b) + " is not one of the network's " +
                                               std::to_string(spec.blocks));
    else if (i > 0 && b <= sub.blocks[i - 1]) p.push_back("blocks must be ascending and distinct");
  }
  if (spec.blocks > 0 && sub.blocks.empty()) p.push_back("keeps no block");
  if (const auto& fixed = backbone_registry().get(spec.backbone).fixed_blocks)
    for (int b : fixed(spec.blocks))
      if (!std::binary_search(sub.blocks.begin(), sub.blocks.end(), b))
        p.push_back("skips block " + std::to_string(b) + ", which every " + spec.backbone + " subnet keeps");
  const auto groups = layer_groups(spec);
  for (const auto& [group, width] : sub.widths) {
    // Named in the capture: C++17 lambdas cannot capture a structured binding (clang refuses).
    const auto it = std::find_if(groups.begin(), groups.end(), [&name = group](const auto& g) { return g.first == name; });
    if (it == groups.end()) {
      p.push_back("no layer group '" + group + "' in " + spec_summary(spec));
      continue;
    }
    if (width < 1 || width > it->second)
      p.push_back("layer group " + group + " keeps " + std::to_string(width) + " channels of " +
                  std::to_string(it->second));
  }
  return p;
}

graph::Graph skip_blocks(const graph::Graph& graph, const std::vector<int>& kept, int total_blocks) {
  if (static_cast<int>(kept.size()) == total_blocks) return graph;
  std::vector<bool> skipped(total_blocks, true);
  for (int b : kept) {
    CGSR_CHECK(b >= 0 && b < total_blocks, "skip_blocks: block " + std::to_string(b) + " out of range");
    skipped[b] = false;
  }
  // Every value's replacement: a skipped block's output becomes the value its ops read from outside.
  std::vector<int> replaced(graph.values.size());
  std::iota(replaced.begin(), replaced.end(), 0);
  std::vector<bool> drop(graph.ops.size(), false);
  for (int b = 0; b < total_blocks; ++b) {
    if (!skipped[b]) continue;
    std::set<int> produced, read;
    for (size_t i = 0; i < graph.ops.size(); ++i)
      if (op_block(graph.ops[i].name) == b) {
        drop[i] = true;
        produced.insert(graph.ops[i].output);
        for (int v : graph.ops[i].inputs) read.insert(v);
      }
    CGSR_CHECK(!produced.empty(), "skip_blocks: the graph has no block " + std::to_string(b));
    std::set<int> from_outside;
    for (int v : read)
      if (!produced.count(v)) from_outside.insert(replaced[v]);
    std::set<int> to_outside;
    for (size_t i = 0; i < graph.ops.size(); ++i)
      if (op_block(graph.ops[i].name) != b)
        for (int v : graph.ops[i].inputs)
          if (produced.count(v)) to_outside.insert(v);
    for (const auto& [name, v] : graph.outputs)
      if (produced.count(v)) to_outside.insert(v);
    CGSR_CHECK(from_outside.size() == 1 && to_outside.size() == 1,
               "skip_blocks: block " + std::to_string(b) + " is not a residual block with one input and one output");
    const int in = *from_outside.begin(), out = *to_outside.begin();
    CGSR_CHECK(graph.values[in].layout == graph.values[out].layout && graph.values[in].factor == graph.values[out].factor,
               "skip_blocks: block " + std::to_string(b) + " changes its input's shape");
    replaced[out] = in;
  }
  std::vector<std::optional<graph::Op>> remaining(graph.ops.size());
  for (size_t i = 0; i < graph.ops.size(); ++i)
    if (!drop[i]) remaining[i] = graph.ops[i];
  return graph::rewrite(graph, remaining, replaced);
}

ChannelSelection subnet_selection(const graph::Graph& graph, const SubnetConfig& sub) {
  ChannelSelection keep;
  for (const auto& [group, width] : group_widths(graph)) {
    const int64_t kept = subnet_width(sub, group, width);
    if (kept == width) continue;
    CGSR_CHECK(kept >= 1 && kept <= width, "subnet: layer group " + group + " keeps " + std::to_string(kept) +
                                               " of " + std::to_string(width) + " channels");
    std::vector<int64_t> prefix(kept);
    std::iota(prefix.begin(), prefix.end(), 0);
    keep[group] = std::move(prefix);
  }
  return keep;
}

graph::Graph subnet_graph(const SRNetworkImpl& net, const SubnetConfig& sub, bool training, bool differentiable) {
  const auto problems = subnet_problems(net.spec(), sub);
  if (!problems.empty()) throw Error("subnet " + subnet_key(sub), join(problems, "; "));
  const graph::Graph full =
      skip_blocks(training ? net.describe(true) : net.describe_branches(), sub.blocks, net.spec().blocks);
  graph::Graph narrowed = select_channels(full, subnet_selection(full, sub), differentiable);
  return training ? narrowed : fold_branch_convs(narrowed);
}

ArchSpec subnet_spec(const ArchSpec& full, const SubnetConfig& sub) {
  const auto problems = subnet_problems(full, sub);
  if (!problems.empty()) throw Error("subnet " + subnet_key(sub), join(problems, "; "));
  ArchSpec spec = full;
  spec.blocks = static_cast<int>(sub.blocks.size());
  GroupWidths widths;
  for (const auto& [group, width] : full.widths.entries()) {
    const auto block = parse_block_group(group);
    if (!block) {
      widths.set(group, static_cast<int>(subnet_width(sub, group, width)));
      continue;
    }
    const auto at = std::lower_bound(sub.blocks.begin(), sub.blocks.end(), block->first);
    if (at == sub.blocks.end() || *at != block->first) continue;
    widths.set(block_group(static_cast<int>(at - sub.blocks.begin()), block->second),
               static_cast<int>(subnet_width(sub, group, width)));
  }
  spec.widths = widths;
  if (spec.rit.enabled) {
    spec.rit.width = static_cast<int>(subnet_width(sub, "rit", full.rit.width));
    spec.rit.hr_width = static_cast<int>(subnet_width(sub, "rit_hr", full.rit.hr_width));
  }
  return resolve_spec(spec);
}

SRNetwork materialize_subnet(const SRNetworkImpl& net, const SubnetConfig& sub, bool geometry_head) {
  ArchSpec spec = subnet_spec(net.spec(), sub);
  if (!geometry_head) spec.geometry.enabled = false;
  std::map<std::string, std::vector<int64_t>> kept;
  for (const auto& [group, width] : layer_groups(net.spec())) {
    const auto block = parse_block_group(group);
    if (block && !kept_block(sub, block->first)) continue;
    std::vector<int64_t> prefix(subnet_width(sub, group, width));
    std::iota(prefix.begin(), prefix.end(), 0);
    kept[group] = std::move(prefix);
  }
  if (net.has_geometry_head() && spec.geometry.enabled) {
    std::vector<int64_t> all(net.spec().geometry.width);
    std::iota(all.begin(), all.end(), 0);
    kept["geometry"] = std::move(all);
  }
  Inheritance child = inherit(net, spec, kept, sub.blocks);
  CGSR_CHECK(child.fresh.empty(), "materialize_subnet: " + join(child.fresh) + " not taken from the network");
  child.network->train(net.is_training());
  return child.network;
}

}  // namespace cgsr
