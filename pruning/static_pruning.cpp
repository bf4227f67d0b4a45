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

StaticPruning static_prune(const SRNetworkImpl& net, const PatternPool& pool, const std::vector<int64_t>& counts,
                           const StaticPruneOptions& options) {
  CGSR_CHECK(counts.size() == static_cast<size_t>(pool.size()), "static_prune: one count per pattern");
  StaticPruning result;
  result.left_out = nlohmann::ordered_json::object();
  for (int k = 0; k < pool.size(); ++k)
    if (counts[k] > 0) result.kept.push_back(k);
  if (result.kept.empty()) throw Error("static pruning", "no frame selected any pattern");
  result.channels = pool.selection(result.kept.front());

  ArchSpec child = net.spec();
  child.geometry.enabled = false;
  auto groups_json = nlohmann::ordered_json::object();
  for (const auto& u : pool.units)
    for (size_t i = 0; i < u.groups.size(); ++i) {
      const int64_t kept = static_cast<int64_t>(result.channels.at(u.groups[i]).size());
      child.set_group_width(u.groups[i], static_cast<int>(kept));
      if (kept < u.widths[i]) groups_json[u.groups[i]] = {{"width", u.widths[i]}, {"kept", kept}};
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

  result.pool = keep_patterns(pool, result.kept, find_units(result.network->describe(false)));

  result.left_out["channels"] = groups_json;
  result.left_out["patterns"] = {{"pool", pool.size()}, {"kept", result.kept}};
  result.left_out["rit_channels"] = rit_json;
  result.left_out["geometry_head"] = net.has_geometry_head();
  return result;
}

}  // namespace cgsr
