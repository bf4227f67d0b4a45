#include "models/inherit.h"

#include <torch/torch.h>

#include <algorithm>
#include <cctype>
#include <numeric>
#include <set>

#include "core/error.h"
#include "core/text.h"
#include "models/backbone_registry.h"
#include "models/importance/channel_importance.h"

namespace cgsr {

namespace {

// Child names -> parent names when child block i is parent block blocks[i] (empty: block i).
class BlockMap {
 public:
  explicit BlockMap(std::vector<int> blocks) : blocks_(std::move(blocks)) {}

  // "block<i>_<suffix>" -> "block<blocks[i]>_<suffix>"; other groups unchanged.
  std::string group(const std::string& name) const {
    const auto block = parse_block_group(name);
    if (!block || !mapped(block->first)) return name;
    return block_group(blocks_[block->first], block->second);
  }
  // "backbone.blocks.<i>.rest" -> "backbone.blocks.<blocks[i]>.rest"; other ops unchanged.
  std::string op(const std::string& name) const {
    static const std::string prefix = "backbone.blocks.";
    if (name.rfind(prefix, 0) != 0) return name;
    const size_t dot = name.find('.', prefix.size());
    if (dot == std::string::npos) return name;
    const std::string index = name.substr(prefix.size(), dot - prefix.size());
    if (index.empty() || index.size() > 6 || !std::all_of(index.begin(), index.end(), [](unsigned char c) { return std::isdigit(c); })) return name;
    const int i = std::stoi(index);
    return mapped(i) ? prefix + std::to_string(blocks_[i]) + name.substr(dot) : name;
  }

 private:
  bool mapped(int i) const { return i >= 0 && i < static_cast<int>(blocks_.size()); }
  std::vector<int> blocks_;
};

void check_block_map(const ArchSpec& parent, const ArchSpec& child, const std::vector<int>& blocks) {
  if (blocks.empty()) return;
  CGSR_CHECK(static_cast<int>(blocks.size()) == child.blocks,
             "inherit: " + std::to_string(blocks.size()) + " parent blocks chosen for a child of " +
                 std::to_string(child.blocks));
  for (size_t i = 0; i < blocks.size(); ++i)
    CGSR_CHECK(blocks[i] >= 0 && blocks[i] < parent.blocks && (i == 0 || blocks[i] > blocks[i - 1]),
               "inherit: the parent blocks of a child must be ascending parent block indices");
}

// The parent blocks a shallower child inherits when the caller names none: the first ones, and
// the backbone's fixed blocks (BackboneInfo::fixed_blocks) always. Empty: block i from block i.
std::vector<int> default_parent_blocks(const ArchSpec& parent, const ArchSpec& child) {
  const auto& fixed_blocks = backbone_registry().get(parent.backbone).fixed_blocks;
  if (!fixed_blocks || child.blocks >= parent.blocks || child.blocks <= 0) return {};
  std::vector<int> blocks = fixed_blocks(parent.blocks);
  for (int b = 0; b < parent.blocks && static_cast<int>(blocks.size()) < child.blocks; ++b)
    if (std::find(blocks.begin(), blocks.end(), b) == blocks.end()) blocks.push_back(b);
  std::sort(blocks.begin(), blocks.end());
  if (static_cast<int>(blocks.size()) != child.blocks) return {};  // too shallow to keep them: a clear error later
  return blocks;
}

}  // namespace

std::vector<std::string> inheritance_problems(const ArchSpec& parent, const ArchSpec& child,
                                              const std::vector<int>& given_blocks) {
  const auto parent_blocks = given_blocks.empty() ? default_parent_blocks(parent, child) : given_blocks;
  std::vector<std::string> p;
  if (child.backbone != parent.backbone)
    p.push_back("backbone " + child.backbone + " differs from the parent's " + parent.backbone);
  if (child.scale != parent.scale)
    p.push_back("scale x" + std::to_string(child.scale) + " differs from the parent's x" + std::to_string(parent.scale));
  if (child.colors != parent.colors)
    p.push_back("colors " + enum_name(child.colors) + " differ from the parent's " + enum_name(parent.colors));
  if (!p.empty()) return p;
  if (child.blocks > parent.blocks)
    p.push_back("child has " + std::to_string(child.blocks) + " blocks, the parent only " +
                std::to_string(parent.blocks));
  if (!p.empty()) return p;
  check_block_map(parent, child, parent_blocks);
  const BlockMap map(parent_blocks);
  for (const auto& [group, width] : child.widths.entries()) {
    const std::string in_parent = map.group(group);
    if (parent.widths.contains(in_parent) && width > parent.widths.at(in_parent))
      p.push_back("layer group " + group + " is " + std::to_string(width) + " wide, the parent's " +
                  (in_parent == group ? "" : in_parent + " ") + "only " + std::to_string(parent.widths.at(in_parent)));
  }
  if (child.rit.enabled && parent.rit.enabled) {
    if (child.rit.source != parent.rit.source)
      p.push_back("rit.source " + enum_name(child.rit.source) + " differs from the parent's " +
                  enum_name(parent.rit.source));
    if (child.rit.fusion != parent.rit.fusion)
      p.push_back("rit.fusion " + enum_name(child.rit.fusion) + " differs from the parent's " +
                  enum_name(parent.rit.fusion));
    for (const auto& c : child.rit.channels)
      if (std::find(parent.rit.channels.begin(), parent.rit.channels.end(), c) == parent.rit.channels.end())
        p.push_back("rit channel " + c + " is not read by the parent (" + join(parent.rit.channels) + ")");
    if (child.rit.depth_encoding != parent.rit.depth_encoding)
      p.push_back("rit.depth_encoding " + enum_name(child.rit.depth_encoding) + " differs from the parent's " +
                  enum_name(parent.rit.depth_encoding));
    if (child.rit.width > parent.rit.width)
      p.push_back("rit.width " + std::to_string(child.rit.width) + " exceeds the parent's " +
                  std::to_string(parent.rit.width));
    if (child.rit.hr_width > parent.rit.hr_width)
      p.push_back("rit.hr_width " + std::to_string(child.rit.hr_width) + " exceeds the parent's " +
                  std::to_string(parent.rit.hr_width));
  }
  if (child.geometry.enabled && parent.geometry.enabled && child.geometry.width > parent.geometry.width)
    p.push_back("geometry.width " + std::to_string(child.geometry.width) + " exceeds the parent's " +
                std::to_string(parent.geometry.width));
  return p;
}

namespace {

// Positions along a parent axis that make up the child axis, in child order.
std::vector<int64_t> axis_indices(const graph::Layout& parent, const graph::Layout& child,
                                  const std::map<std::string, std::vector<int64_t>>& kept, const BlockMap& map,
                                  const std::string& what) {
  std::vector<int64_t> out;
  std::map<std::string, int> seen;  // a group concatenated twice (SPAN's conv_cat): the n-th to the n-th
  for (const auto& cs : child) {
    const std::string group = map.group(cs.group);
    int64_t offset = 0;
    const graph::Segment* ps = nullptr;
    int skip = seen[group]++;
    for (const auto& s : parent) {
      if (s.group == group && skip-- == 0) {
        ps = &s;
        break;
      }
      offset += s.channels * s.repeat;
    }
    CGSR_CHECK(ps && ps->repeat == cs.repeat && ps->prunable == cs.prunable,
               "inherit: " + what + ": channel group " + cs.group + " has no counterpart in the parent");
    std::vector<int64_t> channels;
    if (cs.prunable) {
      channels = kept.at(group);
    } else {
      CGSR_CHECK(ps->channels == cs.channels, "inherit: " + what + ": fixed axis " + cs.group + " changed size");
      channels.resize(cs.channels);
      std::iota(channels.begin(), channels.end(), 0);
    }
    CGSR_CHECK(static_cast<int64_t>(channels.size()) == cs.channels, "inherit: " + what + ": width of " + cs.group);
    for (int64_t c : channels)
      for (int64_t k = 0; k < cs.repeat; ++k) out.push_back(offset + c * cs.repeat + k);
  }
  return out;
}

torch::Tensor take(const torch::Tensor& t, int64_t dim, const std::vector<int64_t>& index) {
  return t.index_select(dim, torch::tensor(index, torch::kLong));
}

// The channels of each group to keep, by the parent's group names: all of them when the width is
// unchanged (so an identical child is an exact copy), else the most important ones in their
// original order.
std::map<std::string, std::vector<int64_t>> choose_channels(const graph::Graph& parent, const graph::Graph& child,
                                                            const std::map<std::string, std::vector<int64_t>>& given,
                                                            const BlockMap& map) {
  const auto importance = channel_importance(parent);
  std::map<std::string, int64_t> child_widths;  // by parent group name
  for (const auto& v : child.values)
    for (const auto& s : v.layout)
      if (s.prunable) child_widths[map.group(s.group)] = s.channels;
  std::map<std::string, std::vector<int64_t>> kept;
  for (const auto& [group, width] : child_widths) {
    const auto it = importance.find(group);
    if (it == importance.end()) continue;  // a group the parent lacks (fresh RIT or head)
    const auto chosen = given.find(group);
    if (chosen != given.end()) {
      const auto& c = chosen->second;
      CGSR_CHECK(static_cast<int64_t>(c.size()) == width,
                 "inherit: group " + group + " is " + std::to_string(width) + " wide but " + std::to_string(c.size()) +
                     " channels were chosen");
      std::vector<bool> seen(it->second.numel(), false);
      for (int64_t i : c) {
        CGSR_CHECK(i >= 0 && i < it->second.numel() && !seen[i],
                   "inherit: chosen channels of group " + group + " must be distinct parent indices");
        seen[i] = true;
      }
      kept[group] = c;
      continue;
    }
    const auto scores = it->second.detach().to(torch::kDouble).contiguous();
    const int64_t n = scores.numel();
    CGSR_CHECK(width <= n, "inherit: group " + group + " grows");
    std::vector<int64_t> order(n);
    std::iota(order.begin(), order.end(), 0);
    const double* s = scores.data_ptr<double>();
    std::stable_sort(order.begin(), order.end(), [s](int64_t a, int64_t b) { return s[a] > s[b]; });
    order.resize(width);
    std::sort(order.begin(), order.end());
    kept[group] = order;
  }
  return kept;
}

bool fresh_allowed(const std::string& name) { return name.rfind("rit.", 0) == 0 || name.rfind("geometry.", 0) == 0; }

}  // namespace

Inheritance inherit(const SRNetworkImpl& parent, const ArchSpec& child_spec) { return inherit(parent, child_spec, {}); }

Inheritance inherit(const SRNetworkImpl& parent, const ArchSpec& child_spec_in,
                    const std::map<std::string, std::vector<int64_t>>& kept, const std::vector<int>& given_blocks) {
  const ArchSpec child_spec = resolve_spec(child_spec_in);
  const auto parent_blocks = given_blocks.empty() ? default_parent_blocks(parent.spec(), child_spec) : given_blocks;
  const auto problems = inheritance_problems(parent.spec(), child_spec, parent_blocks);
  if (!problems.empty())
    throw Error("inherit " + spec_summary(child_spec) + " from " + spec_summary(parent.spec()), join(problems, "; "));

  Inheritance result;
  result.network = SRNetwork(child_spec);
  const graph::Graph pg = parent.describe(/*training=*/true);
  const graph::Graph cg = result.network->describe(/*training=*/true);
  const BlockMap map(parent_blocks);
  std::set<std::string> child_groups = {"rit", "rit_hr", "geometry"};  // by parent group name
  for (const auto& [group, width] : child_spec.widths.entries()) child_groups.insert(map.group(group));
  for (const auto& [group, channels] : kept)
    CGSR_CHECK(child_groups.count(group), "inherit: chosen channels for an unknown layer group " + group);
  result.kept = choose_channels(pg, cg, kept, map);

  torch::NoGradGuard no_grad;
  std::set<const void*> assigned;
  const auto copy = [&](const torch::Tensor& dst, const torch::Tensor& src, const std::string& what) {
    CGSR_CHECK(dst.sizes() == src.sizes(), "inherit: " + what + " shape mismatch");
    dst.copy_(src);
    assigned.insert(dst.unsafeGetTensorImpl());
  };
  for (const auto& op : cg.ops) {
    if (!op.trainable || !graph::op_traits(op.kind).has_tensors) continue;
    const graph::Op* pop = pg.find_op(map.op(op.name));
    if (!pop) {
      CGSR_CHECK(fresh_allowed(op.name), "inherit: the parent has no " + op.name);
      continue;
    }
    const auto out = axis_indices(pg.values[pop->output].layout, cg.values[op.output].layout, result.kept, map,
                                  op.name + " output");
    if (graph::op_traits(op.kind).mixes_channels) {
      CGSR_CHECK(op.groups == 1 && pop->groups == 1, "inherit: grouped convs are not supported");
      const auto in = axis_indices(pg.values[pop->inputs[0]].layout, cg.values[op.inputs[0]].layout, result.kept,
                                   map, op.name + " input");
      copy(op.weight, take(take(pop->weight, 0, out), 1, in), op.name + ".weight");
      if (op.bias.defined()) copy(op.bias, take(pop->bias, 0, out), op.name + ".bias");
    } else {
      if (op.scale.defined()) copy(op.scale, take(pop->scale, 0, out), op.name + " scale");
      if (op.shift.defined()) copy(op.shift, take(pop->shift, 0, out), op.name + " shift");
    }
  }
  for (const auto& p : result.network->named_parameters(/*recurse=*/true)) {
    if (assigned.count(p.value().unsafeGetTensorImpl())) continue;
    CGSR_CHECK(fresh_allowed(p.key()), "inherit: parameter " + p.key() + " is not described by the graph");
    result.fresh.push_back(p.key());
  }
  return result;
}

}  // namespace cgsr
