#include "pruning/pattern_pool.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/text.h"
#include "models/backbone_registry.h"

namespace cgsr {

config::Schema<PoolOptions> pool_schema() {
  config::Schema<PoolOptions> s;
  s.field("latency_factors", &PoolOptions::latency_factors,
          "pattern k: the front point nearest this multiple of the pick's predicted latency")
      .check(
          [](const std::vector<double>& f) {
            if (f.empty()) return false;
            for (size_t i = 0; i < f.size(); ++i)
              if (!(f[i] > 0) || (i > 0 && f[i] >= f[i - 1])) return false;
            return true;
          },
          "must be positive and strictly decreasing (the widest pattern first)");
  return s;
}

double PatternPool::channel_fraction(int k) const {
  CGSR_CHECK(k >= 0 && k < size(), "pattern index " + std::to_string(k) + " out of range");
  const SubnetConfig full = full_subnet(spec);
  double kept = 0, all = 0;
  for (const auto& [group, width] : full.widths) {
    all += static_cast<double>(width);
    const auto block = parse_block_group(group);
    const auto& blocks = patterns[k].blocks;
    if (block && !std::binary_search(blocks.begin(), blocks.end(), block->first)) continue;
    kept += static_cast<double>(subnet_width(patterns[k], group, width));
  }
  return all > 0 ? kept / all : 1.0;
}

PatternPool pool_from_front(const ArchSpec& spec, const std::vector<Candidate>& front, double pick_latency_ms,
                            const PoolOptions& options) {
  if (front.empty()) throw Error("pattern pool", "the search's front is empty");
  PatternPool pool;
  pool.spec = spec;
  std::vector<bool> taken(front.size(), false);
  for (double factor : options.latency_factors) {
    const double target = factor * pick_latency_ms;
    size_t best = front.size();
    for (size_t i = 0; i < front.size(); ++i) {
      if (taken[i]) continue;
      if (best == front.size() || std::abs(front[i].score.latency_ms - target) <
                                      std::abs(front[best].score.latency_ms - target))
        best = i;
    }
    if (best == front.size()) break;
    taken[best] = true;
  }
  // Widest first: the front is fastest first.
  for (size_t i = front.size(); i-- > 0;)
    if (taken[i]) pool.patterns.push_back(front[i].subnet);
  for (const auto& p : pool.patterns) {
    const auto problems = subnet_problems(spec, p);
    if (!problems.empty()) throw Error("pattern pool", subnet_key(p) + ": " + join(problems, "; "));
  }
  return pool;
}

SubnetConfig pool_union(const PatternPool& pool) {
  CGSR_CHECK(pool.size() > 0, "pool_union: an empty pool");
  SubnetConfig out;
  const SubnetConfig full = full_subnet(pool.spec);
  for (const auto& p : pool.patterns)
    for (int b : p.blocks)
      if (std::find(out.blocks.begin(), out.blocks.end(), b) == out.blocks.end()) out.blocks.push_back(b);
  std::sort(out.blocks.begin(), out.blocks.end());
  for (const auto& [group, width] : full.widths) {
    int64_t widest = 0;
    for (const auto& p : pool.patterns) {
      const auto block = parse_block_group(group);
      if (block && !std::binary_search(p.blocks.begin(), p.blocks.end(), block->first)) continue;
      widest = std::max(widest, subnet_width(p, group, width));
    }
    out.widths[group] = widest > 0 ? widest : width;  // a group of a block no pattern keeps
  }
  return out;
}

PatternPool rebase_pool(const PatternPool& pool, const SubnetConfig& onto, const ArchSpec& spec) {
  PatternPool out;
  out.spec = spec;
  const auto position = [&](int block) {
    const auto at = std::lower_bound(onto.blocks.begin(), onto.blocks.end(), block);
    CGSR_CHECK(at != onto.blocks.end() && *at == block, "rebase_pool: block " + std::to_string(block) +
                                                            " is not in the network the pool moves to");
    return static_cast<int>(at - onto.blocks.begin());
  };
  for (const auto& p : pool.patterns) {
    SubnetConfig q;
    for (int b : p.blocks) q.blocks.push_back(position(b));
    for (const auto& [group, width] : p.widths) {
      const auto block = parse_block_group(group);
      if (!block) {
        q.widths[group] = width;
      } else if (std::binary_search(p.blocks.begin(), p.blocks.end(), block->first)) {
        q.widths[block_group(position(block->first), block->second)] = width;
      }
    }
    const auto problems = subnet_problems(spec, q);
    CGSR_CHECK(problems.empty(), "rebase_pool: " + join(problems, "; "));
    out.patterns.push_back(std::move(q));
  }
  return out;
}

PatternPool chosen_patterns(const PatternPool& pool, const std::vector<int64_t>& counts, std::vector<int>& kept) {
  CGSR_CHECK(counts.size() == static_cast<size_t>(pool.size()), "chosen_patterns: one count per pattern");
  PatternPool out;
  out.spec = pool.spec;
  kept.clear();
  for (int k = 0; k < pool.size(); ++k)
    if (counts[k] > 0) {
      kept.push_back(k);
      out.patterns.push_back(pool.patterns[k]);
    }
  if (kept.empty()) throw Error("static pruning", "no frame chose any pattern");
  return out;
}

nlohmann::ordered_json to_json(const PatternPool& pool) {
  auto patterns = nlohmann::ordered_json::array();
  for (const auto& p : pool.patterns) patterns.push_back(to_json(p));
  return {{"patterns", patterns}};
}

PatternPool pool_from_json(const nlohmann::ordered_json& j, const ArchSpec& spec, const std::string& context) {
  PatternPool pool;
  pool.spec = spec;
  try {
    const auto& jp = j.at("patterns");
    if (!jp.is_array() || jp.empty()) throw Error(context, "the pattern pool has no pattern");
    for (size_t k = 0; k < jp.size(); ++k) {
      SubnetConfig p = subnet_from_json(jp[k], context + ": pattern " + std::to_string(k));
      const auto problems = subnet_problems(spec, p);
      if (!problems.empty())
        throw Error(context, "pattern " + std::to_string(k) + " is not a subnet of the network: " + join(problems, "; "));
      pool.patterns.push_back(std::move(p));
    }
  } catch (const nlohmann::json::exception& e) {
    throw Error(context, std::string("malformed pattern pool: ") + e.what());
  }
  return pool;
}

}  // namespace cgsr
