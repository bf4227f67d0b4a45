#include "pruning/pattern_pool.h"

#include <torch/torch.h>

#include <algorithm>
#include <bitset>
#include <cmath>
#include <numeric>

#include "core/error.h"

namespace cgsr {

config::Schema<PoolOptions> pool_schema() {
  config::Schema<PoolOptions> s;
  s.field("keep_rate", &PoolOptions::keep_rate, "fraction of each group's channels a pattern keeps")
      .check([](double v) { return v > 0 && v <= 1; }, "must be in (0, 1]");
  s.field("size", &PoolOptions::size, "patterns per unit (K)").range(1, 64);
  s.field("merge_tolerance", &PoolOptions::merge_tolerance,
          "fraction of a pattern's channels two frame patterns may differ in and still merge (0 = exact)")
      .range(0.0, 1.0);
  return s;
}

ChannelSelection PatternPool::selection(const std::vector<int>& choice) const {
  CGSR_CHECK(choice.size() == units.size(), "pattern choice has the wrong number of units");
  ChannelSelection out;
  for (size_t u = 0; u < units.size(); ++u) {
    CGSR_CHECK(choice[u] >= 0 && choice[u] < static_cast<int>(units[u].patterns.size()),
               "pattern index out of range for unit " + units[u].unit.name);
    for (const auto& [g, c] : units[u].patterns[choice[u]].keep) out[g] = c;
  }
  return out;
}

ChannelSelection PatternPool::union_selection() const {
  ChannelSelection out;
  for (const auto& u : units)
    for (const auto& g : u.unit.groups) {
      std::vector<int64_t> all;
      for (const auto& p : u.patterns) all.insert(all.end(), p.keep.at(g).begin(), p.keep.at(g).end());
      std::sort(all.begin(), all.end());
      all.erase(std::unique(all.begin(), all.end()), all.end());
      out[g] = all;
    }
  return out;
}

int PatternPool::max_patterns() const {
  int k = 0;
  for (const auto& u : units) k = std::max(k, static_cast<int>(u.patterns.size()));
  return k;
}

namespace {
std::vector<double> as_vector(const torch::Tensor& t) {
  const auto c = t.detach().to(torch::kDouble).contiguous();
  return std::vector<double>(c.data_ptr<double>(), c.data_ptr<double>() + c.numel());
}

// A unit pattern as a bit set over the unit's concatenated group channels.
using Bits = std::vector<uint64_t>;

Bits to_bits(const PrunableUnit& unit, const ChannelSelection& keep) {
  Bits bits((unit.total_width() + 63) / 64, 0);
  int64_t offset = 0;
  for (size_t i = 0; i < unit.groups.size(); ++i) {
    for (int64_t c : keep.at(unit.groups[i])) bits[(offset + c) / 64] |= uint64_t{1} << ((offset + c) % 64);
    offset += unit.widths[i];
  }
  return bits;
}

int distance(const Bits& a, const Bits& b) {  // channels in a and not in b
  int d = 0;
  for (size_t i = 0; i < a.size(); ++i) d += static_cast<int>(std::bitset<64>(a[i] & ~b[i]).count());
  return d;
}
}  // namespace

ChannelSelection top_channels(const PrunableUnit& unit, const FrameImportance& importance, double keep_rate) {
  ChannelSelection keep;
  for (size_t i = 0; i < unit.groups.size(); ++i) {
    const auto& g = unit.groups[i];
    const auto it = importance.find(g);
    if (it == importance.end()) throw Error("pattern pool", "no importance for layer group " + g, ErrorKind::Internal);
    const auto scores = as_vector(it->second);
    CGSR_CHECK(static_cast<int64_t>(scores.size()) == unit.widths[i], "importance of " + g + " has the wrong size");
    std::vector<int64_t> order(scores.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](int64_t a, int64_t b) { return scores[a] > scores[b]; });
    order.resize(kept_count(unit.widths[i], keep_rate));
    std::sort(order.begin(), order.end());
    keep[g] = order;
  }
  return keep;
}

PoolBuild build_pattern_pool(const std::vector<PrunableUnit>& units, const std::vector<FrameImportance>& frames,
                             const PoolOptions& options) {
  if (frames.empty()) throw Error("pattern pool", "no frames to sort patterns over");
  PoolBuild build;
  build.assignment.assign(frames.size(), std::vector<int>(units.size(), 0));
  const size_t n = frames.size();
  for (size_t u = 0; u < units.size(); ++u) {
    const PrunableUnit& unit = units[u];
    std::vector<ChannelSelection> own(n);
    std::vector<Bits> bits(n);
    for (size_t f = 0; f < n; ++f) {
      own[f] = top_channels(unit, frames[f], options.keep_rate);
      bits[f] = to_bits(unit, own[f]);
    }
    int kept = 0;
    for (const auto& [g, c] : own[0]) kept += static_cast<int>(c.size());
    const int tolerance = static_cast<int>(std::floor(options.merge_tolerance * kept + 1e-9));

    UnitPatterns entry;
    entry.unit = unit;
    std::vector<Bits> entry_bits;
    std::vector<bool> covered(n, false);
    while (static_cast<int>(entry.patterns.size()) < options.size) {
      int best = -1, best_support = -1, best_exact = -1;
      for (size_t f = 0; f < n; ++f) {
        if (covered[f]) continue;
        int support = 0, exact = 0;
        for (size_t g = 0; g < n; ++g) {
          if (covered[g]) continue;
          const int d = distance(bits[f], bits[g]);
          support += d <= tolerance;
          exact += d == 0;
        }
        if (support > best_support || (support == best_support && exact > best_exact)) {
          best = static_cast<int>(f);
          best_support = support;
          best_exact = exact;
        }
      }
      if (best < 0) break;  // every frame covered
      std::vector<size_t> members;
      for (size_t g = 0; g < n; ++g)
        if (!covered[g] && distance(bits[best], bits[g]) <= tolerance) members.push_back(g);
      // Consensus: per group the most often selected channels (frequency-based sorting).
      Pattern pattern;
      pattern.frames = static_cast<int>(members.size());
      for (size_t i = 0; i < unit.groups.size(); ++i) {
        const auto& group = unit.groups[i];
        std::vector<int> count(unit.widths[i], 0);
        std::vector<double> weight(unit.widths[i], 0.0);
        for (size_t m : members) {
          for (int64_t c : own[m].at(group)) ++count[c];
          const auto s = as_vector(frames[m].at(group));
          const double total = std::accumulate(s.begin(), s.end(), 0.0);
          for (int64_t c = 0; c < unit.widths[i]; ++c) weight[c] += total > 0 ? s[c] / total : 0.0;
        }
        std::vector<int64_t> order(unit.widths[i]);
        std::iota(order.begin(), order.end(), 0);
        std::stable_sort(order.begin(), order.end(), [&](int64_t a, int64_t b) {
          return count[a] != count[b] ? count[a] > count[b] : weight[a] > weight[b];
        });
        order.resize(own[best].at(group).size());
        std::sort(order.begin(), order.end());
        pattern.keep[group] = order;
      }
      for (size_t m : members) covered[m] = true;
      entry_bits.push_back(to_bits(unit, pattern.keep));
      entry.patterns.push_back(std::move(pattern));
    }
    // Frequencies and assignment by nearest entry (ties: the more frequent, i.e. earlier, one).
    for (auto& p : entry.patterns) p.frames = 0;
    for (size_t f = 0; f < n; ++f) {
      int nearest = 0, nearest_d = distance(entry_bits[0], bits[f]);
      for (size_t k = 1; k < entry_bits.size(); ++k) {
        const int d = distance(entry_bits[k], bits[f]);
        if (d < nearest_d) {
          nearest = static_cast<int>(k);
          nearest_d = d;
        }
      }
      build.assignment[f][u] = nearest;
      ++entry.patterns[nearest].frames;
    }
    // Most frequent first; remap the assignment.
    std::vector<int> order(entry.patterns.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(),
                     [&](int a, int b) { return entry.patterns[a].frames > entry.patterns[b].frames; });
    std::vector<int> rank(order.size());
    std::vector<Pattern> sorted;
    for (size_t r = 0; r < order.size(); ++r) {
      rank[order[r]] = static_cast<int>(r);
      sorted.push_back(entry.patterns[order[r]]);
    }
    entry.patterns = std::move(sorted);
    for (size_t f = 0; f < n; ++f) build.assignment[f][u] = rank[build.assignment[f][u]];
    build.pool.units.push_back(std::move(entry));
  }
  return build;
}

nlohmann::ordered_json to_json(const PatternPool& pool) {
  auto units = nlohmann::ordered_json::array();
  for (const auto& u : pool.units) {
    nlohmann::ordered_json ju;
    ju["unit"] = u.unit.name;
    ju["groups"] = u.unit.groups;
    ju["widths"] = u.unit.widths;
    ju["patterns"] = nlohmann::ordered_json::array();
    for (const auto& p : u.patterns) {
      nlohmann::ordered_json jp;
      jp["frames"] = p.frames;
      jp["keep"] = nlohmann::ordered_json::object();
      for (const auto& g : u.unit.groups) jp["keep"][g] = p.keep.at(g);
      ju["patterns"].push_back(jp);
    }
    units.push_back(ju);
  }
  return {{"units", units}};
}

PatternPool pool_from_json(const nlohmann::ordered_json& j, const std::vector<PrunableUnit>& units,
                           const std::string& context) {
  PatternPool pool;
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
      UnitPatterns up;
      up.unit = units[u];
      for (const auto& jp : e.at("patterns")) {
        Pattern p;
        p.frames = jp.at("frames").get<int>();
        for (size_t i = 0; i < units[u].groups.size(); ++i) {
          const auto& g = units[u].groups[i];
          auto c = jp.at("keep").at(g).get<std::vector<int64_t>>();
          for (size_t k = 0; k < c.size(); ++k)
            if (c[k] < 0 || c[k] >= units[u].widths[i] || (k > 0 && c[k] <= c[k - 1]))
              throw Error(context, "pattern of unit " + units[u].name + " lists invalid channels of " + g);
          if (c.empty()) throw Error(context, "pattern of unit " + units[u].name + " keeps no channel of " + g);
          p.keep[g] = std::move(c);
        }
        up.patterns.push_back(std::move(p));
      }
      if (up.patterns.empty()) throw Error(context, "unit " + units[u].name + " has no pattern");
      pool.units.push_back(std::move(up));
    }
  } catch (const nlohmann::json::exception& e) {
    throw Error(context, std::string("malformed pattern pool: ") + e.what());
  }
  return pool;
}

}  // namespace cgsr
