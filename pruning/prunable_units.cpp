#include "pruning/prunable_units.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <regex>
#include <set>

#include "core/error.h"
#include "core/text.h"

namespace cgsr {

int64_t PrunableUnit::width(const std::string& group) const {
  for (size_t i = 0; i < groups.size(); ++i)
    if (groups[i] == group) return widths[i];
  throw Error("unit " + name, "has no layer group " + group, ErrorKind::Internal);
}

int64_t PrunableUnit::total_width() const { return std::accumulate(widths.begin(), widths.end(), int64_t{0}); }

std::vector<std::string> unit_groups(const std::vector<PrunableUnit>& units) {
  std::vector<std::string> groups;
  for (const auto& u : units) groups.insert(groups.end(), u.groups.begin(), u.groups.end());
  return groups;
}

int64_t kept_count(int64_t width, double keep_rate) {
  return std::clamp<int64_t>(std::llround(keep_rate * static_cast<double>(width)), 1, width);
}

namespace {
std::set<std::string> prunable_groups(const graph::Layout& layout) {
  std::set<std::string> out;
  for (const auto& s : layout)
    if (s.prunable) out.insert(s.group);
  return out;
}

// Union-find over group names.
struct Components {
  std::map<std::string, std::string> parent;
  std::string find(const std::string& g) {
    auto it = parent.find(g);
    if (it == parent.end()) return parent[g] = g;
    if (it->second == g) return g;
    return it->second = find(it->second);
  }
  void unite(const std::string& a, const std::string& b) { parent[find(a)] = find(b); }
};

std::string unit_name(const std::vector<std::string>& groups) {
  static const std::regex block(R"(block(\d+)_.*)");
  std::string index;
  for (const auto& g : groups) {
    std::smatch m;
    if (!std::regex_match(g, m, block) || (!index.empty() && m[1] != index)) return join(groups, "+");
    index = m[1];
  }
  return "block" + index;
}
}  // namespace

std::vector<PrunableUnit> find_units(const graph::Graph& graph) {
  // Groups that must stay: residual streams (in an addition) and what leaves the graph.
  std::set<std::string> fixed = {"geometry"};
  for (const auto& op : graph.ops)
    if (op.kind == graph::OpKind::Add)
      for (const auto& g : prunable_groups(graph.values[op.output].layout)) fixed.insert(g);
  for (const auto& [name, v] : graph.outputs)
    for (const auto& g : prunable_groups(graph.values[v].layout)) fixed.insert(g);

  std::vector<std::string> order;  // dynamic groups by first appearance
  std::map<std::string, int64_t> widths;
  for (const auto& v : graph.values)
    for (const auto& s : v.layout)
      if (s.prunable && !fixed.count(s.group) && !widths.count(s.group)) {
        order.push_back(s.group);
        widths[s.group] = s.channels;
      }

  Components components;
  for (const auto& g : order) components.find(g);
  for (const auto& op : graph.ops) {
    if (!graph::op_traits(op.kind).mixes_channels) continue;  // element-wise ops keep channel c as channel c
    std::vector<std::string> touched;
    for (const auto& g : prunable_groups(graph.values[op.inputs[0]].layout))
      if (widths.count(g)) touched.push_back(g);
    for (const auto& g : prunable_groups(graph.values[op.output].layout))
      if (widths.count(g)) touched.push_back(g);
    for (size_t i = 1; i < touched.size(); ++i) components.unite(touched[0], touched[i]);
  }

  std::vector<PrunableUnit> units;
  std::map<std::string, size_t> unit_of_root;
  for (const auto& g : order) {
    const std::string root = components.find(g);
    auto it = unit_of_root.find(root);
    if (it == unit_of_root.end()) {
      it = unit_of_root.emplace(root, units.size()).first;
      units.emplace_back();
    }
    units[it->second].groups.push_back(g);
    units[it->second].widths.push_back(widths[g]);
  }
  for (auto& u : units) u.name = unit_name(u.groups);

  for (size_t index = 0; index < graph.ops.size(); ++index) {
    const auto& op = graph.ops[index];
    const auto traits = graph::op_traits(op.kind);
    if (!traits.has_tensors) continue;
    auto groups = prunable_groups(graph.values[op.output].layout);
    if (traits.mixes_channels)
      for (const auto& g : prunable_groups(graph.values[op.inputs[0]].layout)) groups.insert(g);
    int owners = 0;
    for (auto& u : units)
      if (std::any_of(u.groups.begin(), u.groups.end(), [&](const std::string& g) { return groups.count(g) > 0; })) {
        u.ops.push_back(index);
        ++owners;
      }
    // Only an element-wise op over values of two units could do this; no network has one.
    CGSR_CHECK(owners <= 1, "find_units: op " + op.name + " touches two pruning units");
  }
  return units;
}

}  // namespace cgsr
