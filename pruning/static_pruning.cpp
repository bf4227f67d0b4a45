#include "pruning/static_pruning.h"

#include <torch/torch.h>

#include <algorithm>

#include "core/error.h"

namespace cgsr {

config::Schema<StaticPruneOptions> static_prune_schema() {
  config::Schema<StaticPruneOptions> s;
  s.field("rit_threshold", &StaticPruneOptions::rit_threshold,
          "RIT rendering channels contributing less than this fraction of the largest one are left out (0 = keep "
          "all)")
      .range(0.0, 1.0);
  return s;
}

std::vector<std::pair<std::string, double>> rit_channel_contributions(const SRNetworkImpl& net) {
  std::vector<std::pair<std::string, double>> out;
  if (!net.has_rit()) return out;
  torch::NoGradGuard no_grad;
  const auto gate = net.rit_gate().abs();
  // Per info position: what the RIT's convolutions (feature and HR part) read from it.
  const auto& rit = *net.rit();
  auto reads = torch::zeros_like(gate);
  if (rit.has_feature_branch()) reads += rit.conv->weight.abs().sum({0, 2, 3});
  if (rit.has_hr_branch()) reads += rit.hr_conv->weight.abs().sum({0, 2, 3});
  const auto per_position = (gate * reads).to(torch::kDouble);
  int64_t offset = 0;
  for (auto c : net.input_channels()) {
    const int64_t w = channel_width(c);
    out.emplace_back(channel_name(c), per_position.slice(0, offset, offset + w).sum().item<double>());
    offset += w;
  }
  return out;
}

StaticPruning static_prune(const SRNetworkImpl& net, const PatternPool& pool,
                           const std::vector<std::vector<int64_t>>& counts, const StaticPruneOptions& options) {
  CGSR_CHECK(counts.size() == pool.units.size(), "static_prune: one count list per unit");
  StaticPruning result;
  result.left_out = nlohmann::ordered_json::object();
  auto groups_json = nlohmann::ordered_json::object();
  auto patterns_json = nlohmann::ordered_json::object();

  PatternPool selected;
  for (size_t u = 0; u < pool.units.size(); ++u) {
    const auto& up = pool.units[u];
    CGSR_CHECK(counts[u].size() == up.patterns.size(), "static_prune: counts of unit " + up.unit.name);
    std::vector<int> kept;
    for (size_t k = 0; k < up.patterns.size(); ++k)
      if (counts[u][k] > 0) kept.push_back(static_cast<int>(k));
    if (kept.empty()) throw Error("static pruning", "no frame selected any pattern of unit " + up.unit.name);
    UnitPatterns s;
    s.unit = up.unit;
    for (int k : kept) {
      Pattern p = up.patterns[k];
      p.frames = static_cast<int>(counts[u][k]);
      s.patterns.push_back(std::move(p));
    }
    patterns_json[up.unit.name] = {{"pool", up.patterns.size()}, {"kept", kept.size()}};
    result.kept.push_back(kept);
    selected.units.push_back(std::move(s));
  }
  result.channels = selected.union_selection();

  ArchSpec child = net.spec();
  child.geometry.enabled = false;
  for (const auto& u : selected.units)
    for (size_t i = 0; i < u.unit.groups.size(); ++i) {
      const auto& g = u.unit.groups[i];
      const auto& kept = result.channels.at(g);
      child.set_group_width(g, static_cast<int>(kept.size()));
      std::vector<int64_t> removed;
      for (int64_t c = 0, k = 0; c < u.unit.widths[i]; ++c) {
        if (k < static_cast<int64_t>(kept.size()) && kept[k] == c)
          ++k;
        else
          removed.push_back(c);
      }
      groups_json[g] = {{"width", u.unit.widths[i]}, {"kept", kept.size()}, {"removed", removed}};
    }

  auto rit_json = nlohmann::ordered_json::array();
  if (net.has_rit() && options.rit_threshold > 0) {
    const auto contributions = rit_channel_contributions(net);
    double largest = 0;
    for (const auto& [name, v] : contributions) largest = std::max(largest, v);
    std::vector<std::string> keep;
    for (const auto& [name, v] : contributions) {
      if (v >= options.rit_threshold * largest && v > 0) {
        keep.push_back(name);
      } else {
        result.rit_channels_dropped.push_back(name);
        rit_json.push_back({{"channel", name}, {"contribution", largest > 0 ? v / largest : 0.0}});
      }
    }
    if (keep.empty()) {  // a RIT reads at least one channel: keep the strongest
      const auto strongest = std::max_element(contributions.begin(), contributions.end(),
                                              [](const auto& a, const auto& b) { return a.second < b.second; });
      keep.push_back(strongest->first);
      result.rit_channels_dropped.erase(
          std::find(result.rit_channels_dropped.begin(), result.rit_channels_dropped.end(), strongest->first));
      rit_json.erase(std::remove_if(rit_json.begin(), rit_json.end(),
                                    [&](const auto& j) { return j["channel"] == strongest->first; }),
                     rit_json.end());
    }
    child.rit.channels = keep;
  }

  result.network = inherit(net, resolve_spec(child), result.channels).network;
  result.network->eval();

  // The pool in the smaller network's channel indices.
  for (auto& u : selected.units) {
    for (auto& p : u.patterns)
      for (auto& [g, channels] : p.keep) {
        const auto& kept = result.channels.at(g);
        for (auto& c : channels) c = std::lower_bound(kept.begin(), kept.end(), c) - kept.begin();
      }
    for (size_t i = 0; i < u.unit.groups.size(); ++i)
      u.unit.widths[i] = static_cast<int64_t>(result.channels.at(u.unit.groups[i]).size());
  }
  const auto units = find_units(result.network->describe(false));
  CGSR_CHECK(units.size() == selected.units.size(), "static_prune: the pruned network has different units");
  for (size_t u = 0; u < units.size(); ++u) {
    CGSR_CHECK(units[u].groups == selected.units[u].unit.groups && units[u].widths == selected.units[u].unit.widths,
               "static_prune: unit " + units[u].name + " changed shape");
    selected.units[u].unit = units[u];
  }
  result.pool = std::move(selected);

  result.left_out["channels"] = groups_json;
  result.left_out["patterns"] = patterns_json;
  result.left_out["rit_channels"] = rit_json;
  result.left_out["geometry_head"] = net.has_geometry_head();
  return result;
}

}  // namespace cgsr
