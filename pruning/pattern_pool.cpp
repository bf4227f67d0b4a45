#include "pruning/pattern_pool.h"

#include <torch/torch.h>

#include <algorithm>
#include <numeric>

#include "core/error.h"

namespace cgsr {

config::Schema<PoolOptions> pool_schema() {
  config::Schema<PoolOptions> s;
  s.field("keep_rates", &PoolOptions::keep_rates,
          "per pattern, the fraction of every unit group's channels it keeps (widest first, strictly decreasing)")
      .check(
          [](const std::vector<double>& v) {
            if (v.empty()) return false;
            for (size_t i = 0; i < v.size(); ++i)
              if (!(v[i] > 0 && v[i] <= 1) || (i > 0 && v[i] >= v[i - 1])) return false;
            return true;
          },
          "must be strictly decreasing rates in (0, 1]");
  return s;
}

ChannelSelection PatternPool::selection(int k) const {
  CGSR_CHECK(k >= 0 && k < size(), "pattern index " + std::to_string(k) + " out of range");
  ChannelSelection out;
  for (const auto& [group, width] : widths[k]) {
    std::vector<int64_t> c(width);
    std::iota(c.begin(), c.end(), 0);
    out[group] = std::move(c);
  }
  return out;
}

double PatternPool::channel_fraction(int k) const {
  CGSR_CHECK(k >= 0 && k < size(), "pattern index " + std::to_string(k) + " out of range");
  int64_t kept = 0, total = 0;
  for (const auto& u : units) {
    for (size_t i = 0; i < u.groups.size(); ++i) {
      kept += widths[k].at(u.groups[i]);
      total += u.widths[i];
    }
  }
  return total ? static_cast<double>(kept) / static_cast<double>(total) : 1.0;
}

PatternPool nested_pool(const std::vector<PrunableUnit>& units, const std::vector<double>& keep_rates) {
  if (keep_rates.empty()) throw Error("pattern pool", "needs at least one keep rate");
  PatternPool pool;
  pool.units = units;
  for (size_t k = 0; k < keep_rates.size(); ++k) {
    const double rate = keep_rates[k];
    if (!(rate > 0 && rate <= 1) || (k > 0 && rate >= keep_rates[k - 1]))
      throw Error("pattern pool", "keep rates must be strictly decreasing in (0, 1]");
    std::map<std::string, int64_t> w;
    for (const auto& u : units)
      for (size_t i = 0; i < u.groups.size(); ++i) w[u.groups[i]] = kept_count(u.widths[i], rate);
    if (k > 0 && w == pool.widths.back())
      throw Error("pattern pool", "keep rates " + std::to_string(keep_rates[k - 1]) + " and " + std::to_string(rate) +
                                      " keep the same channels of every group (the groups are too narrow)");
    pool.widths.push_back(std::move(w));
  }
  return pool;
}

PatternPool keep_patterns(const PatternPool& pool, const std::vector<int>& kept,
                          const std::vector<PrunableUnit>& narrowed_units) {
  CGSR_CHECK(!kept.empty(), "keep_patterns: keep at least one pattern");
  PatternPool out;
  out.units = narrowed_units;
  for (size_t i = 0; i < kept.size(); ++i) {
    CGSR_CHECK(kept[i] >= 0 && kept[i] < pool.size() && (i == 0 || kept[i] > kept[i - 1]),
               "keep_patterns: pattern indices must be increasing and in range");
    out.widths.push_back(pool.widths[kept[i]]);
  }
  for (const auto& u : out.units)
    for (size_t i = 0; i < u.groups.size(); ++i)
      CGSR_CHECK(out.widths.front().at(u.groups[i]) == u.widths[i],
                 "keep_patterns: the narrowed network must keep the widest pattern's channels of " + u.groups[i]);
  return out;
}

ChannelSelection importance_order(const std::vector<PrunableUnit>& units,
                                  const std::vector<FrameImportance>& frames) {
  if (frames.empty()) throw Error("pattern pool", "no frames to rank channels on");
  ChannelSelection order;
  for (const auto& u : units)
    for (size_t i = 0; i < u.groups.size(); ++i) {
      const auto& g = u.groups[i];
      auto total = torch::zeros({u.widths[i]}, torch::kDouble);
      for (const auto& f : frames) {
        const auto it = f.find(g);
        if (it == f.end()) throw Error("pattern pool", "no importance for layer group " + g, ErrorKind::Internal);
        const auto s = it->second.detach().to(torch::kDouble).flatten();
        CGSR_CHECK(s.numel() == u.widths[i], "importance of " + g + " has the wrong size");
        const double sum = s.sum().item<double>();
        if (sum > 0 && std::isfinite(sum)) total += s / sum;
      }
      const auto t = total.contiguous();
      const double* p = t.data_ptr<double>();
      std::vector<int64_t> idx(u.widths[i]);
      std::iota(idx.begin(), idx.end(), 0);
      std::stable_sort(idx.begin(), idx.end(), [p](int64_t a, int64_t b) { return p[a] > p[b]; });
      order[g] = std::move(idx);
    }
  return order;
}

Inheritance order_channels(const SRNetworkImpl& net, const ChannelSelection& order) {
  Inheritance result = inherit(net, net.spec(), order);
  result.network->train(net.is_training());
  return result;
}

nlohmann::ordered_json to_json(const PatternPool& pool) {
  auto units = nlohmann::ordered_json::array();
  for (const auto& u : pool.units) units.push_back({{"unit", u.name}, {"groups", u.groups}, {"widths", u.widths}});
  auto patterns = nlohmann::ordered_json::array();
  for (const auto& w : pool.widths) {
    nlohmann::ordered_json p = nlohmann::ordered_json::object();
    for (const auto& u : pool.units)
      for (const auto& g : u.groups) p[g] = w.at(g);
    patterns.push_back(p);
  }
  return {{"units", units}, {"patterns", patterns}};
}

PatternPool pool_from_json(const nlohmann::ordered_json& j, const std::vector<PrunableUnit>& units,
                           const std::string& context) {
  PatternPool pool;
  pool.units = units;
  try {
    const auto& ju = j.at("units");
    if (!ju.is_array() || ju.size() != units.size())
      throw Error(context, "the pattern pool has " + std::to_string(ju.is_array() ? ju.size() : 0) +
                               " units, the network " + std::to_string(units.size()));
    for (size_t u = 0; u < units.size(); ++u) {
      const auto& e = ju[u];
      if (e.at("unit").get<std::string>() != units[u].name ||
          e.at("groups").get<std::vector<std::string>>() != units[u].groups ||
          e.at("widths").get<std::vector<int64_t>>() != units[u].widths)
        throw Error(context, "pattern pool unit " + std::to_string(u) + " (" + e.at("unit").get<std::string>() +
                                 ") does not match the network's unit " + units[u].name);
    }
    const auto& jp = j.at("patterns");
    if (!jp.is_array() || jp.empty()) throw Error(context, "the pattern pool has no pattern");
    for (size_t k = 0; k < jp.size(); ++k) {
      std::map<std::string, int64_t> w;
      for (const auto& u : units)
        for (size_t i = 0; i < u.groups.size(); ++i) {
          const auto c = jp[k].at(u.groups[i]).get<int64_t>();
          if (c < 1 || c > u.widths[i])
            throw Error(context, "pattern " + std::to_string(k) + " keeps " + std::to_string(c) + " channels of " +
                                     u.groups[i] + ", which has " + std::to_string(u.widths[i]));
          if (k > 0 && c > pool.widths.back().at(u.groups[i]))
            throw Error(context, "pattern " + std::to_string(k) + " is wider than pattern " + std::to_string(k - 1) +
                                     " in " + u.groups[i] + " (patterns are nested, widest first)");
          w[u.groups[i]] = c;
        }
      pool.widths.push_back(std::move(w));
    }
  } catch (const nlohmann::json::exception& e) {
    throw Error(context, std::string("malformed pattern pool: ") + e.what());
  }
  return pool;
}

}  // namespace cgsr
