#include "models/elastic.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/error.h"
#include "core/text.h"
#include "models/backbone_registry.h"
#include "models/importance/block_importance.h"
#include "models/importance/channel_importance.h"
#include "models/inherit.h"

namespace cgsr {

config::Schema<ElasticOptions> elastic_options_schema() {
  config::Schema<ElasticOptions> s;
  s.field("quantum", &ElasticOptions::quantum, "elastic widths are multiples of this (and the full width)").range(1, 1024);
  s.field("min_width_fraction", &ElasticOptions::min_width_fraction, "the narrowest width, as a fraction of the full one")
      .range(0.01, 1);
  s.field("min_blocks", &ElasticOptions::min_blocks, "the fewest residual blocks a subnet keeps").range(1, 1024);
  s.field("elastic_width", &ElasticOptions::elastic_width, "subnets may narrow layer groups");
  s.field("elastic_depth", &ElasticOptions::elastic_depth, "subnets may skip residual blocks");
  s.field("fixed_groups", &ElasticOptions::fixed_groups, "layer groups that always keep every channel");
  s.field("precisions", &ElasticOptions::precisions,
          "formats a subnet may run in (fp32, bf16, int8): a latency table for each, the search picks one");
  // Configs written before the option hash as they did, so their cached stages stay valid.
  s.omit_when("precisions", [](const ElasticOptions& o) { return o.precisions == std::vector{Precision::Fp32}; });
  s.validate([](const ElasticOptions& o, const config::Cursor& at, const YAML::Node& node) {
    if (o.precisions.empty() || o.precisions.front() != Precision::Fp32)
      at.child("precisions").fail(node["precisions"], "must start with fp32 (the full network's format)");
    for (size_t i = 1; i < o.precisions.size(); ++i)
      if (std::find(o.precisions.begin(), o.precisions.begin() + i, o.precisions[i]) != o.precisions.begin() + i)
        at.child("precisions").fail(node["precisions"], "lists " + enum_name(o.precisions[i]) + " twice");
  });
  return s;
}

namespace {

// Index of the allowed width a fraction `f` of the way from the full width (0) to the smallest (1).
size_t limit_index(size_t choices, double f) {
  const double from_top = std::clamp(f, 0.0, 1.0) * static_cast<double>(choices - 1);
  return choices - 1 - static_cast<size_t>(std::floor(from_top + 1e-9));
}
}  // namespace

ElasticSpace::ElasticSpace(const ArchSpec& spec, ElasticOptions options, std::vector<int> block_order)
    : spec_(resolve_spec(spec)), options_(std::move(options)), block_order_(std::move(block_order)) {
  if (block_order_.empty()) {
    block_order_.resize(std::max(spec_.blocks, 0));
    std::iota(block_order_.begin(), block_order_.end(), 0);
  }
  std::vector<int> sorted = block_order_;
  std::sort(sorted.begin(), sorted.end());
  std::vector<int> expected(std::max(spec_.blocks, 0));
  std::iota(expected.begin(), expected.end(), 0);
  if (sorted != expected)
    throw Error("elastic space", "the block order must list each of the network's " + std::to_string(spec_.blocks) +
                                     " blocks once");
  // Blocks no subnet may skip lead the order, so the smallest subnet keeps them too.
  if (const auto& fixed = backbone_registry().get(spec_.backbone).fixed_blocks) fixed_blocks_ = fixed(spec_.blocks);
  std::stable_partition(block_order_.begin(), block_order_.end(), [&](int b) { return is_fixed_block(b); });
  if (options_.precisions.empty()) throw Error("elastic space: precisions", "lists no precision");
  const auto groups = layer_groups(spec_);
  for (const auto& g : options_.fixed_groups)
    if (std::none_of(groups.begin(), groups.end(), [&](const auto& x) { return x.first == g; }))
      throw Error("elastic space: fixed_groups", "no layer group '" + g + "' in " + spec_summary(spec_));
  for (const auto& [group, full] : groups) {
    Gene gene{group, full, {}};
    const bool fixed = !options_.elastic_width ||
                       std::find(options_.fixed_groups.begin(), options_.fixed_groups.end(), group) !=
                           options_.fixed_groups.end();
    if (!fixed) {
      const auto lowest = std::max<int64_t>(1, static_cast<int64_t>(std::ceil(options_.min_width_fraction * full - 1e-9)));
      for (int64_t w = options_.quantum; w < full; w += options_.quantum)
        if (w >= lowest) gene.choices.push_back(w);
    }
    gene.choices.push_back(full);
    genes_.push_back(std::move(gene));
  }
}

int ElasticSpace::min_blocks() const {
  if (!options_.elastic_depth) return spec_.blocks;
  return std::max(static_cast<int>(fixed_blocks_.size()), std::min(spec_.blocks, options_.min_blocks));
}

bool ElasticSpace::is_fixed_block(int block) const {
  return std::find(fixed_blocks_.begin(), fixed_blocks_.end(), block) != fixed_blocks_.end();
}

SubnetConfig ElasticSpace::full() const { return full_subnet(spec_); }

SubnetConfig ElasticSpace::smallest(ShrinkLimits limits) const {
  SubnetConfig sub;
  sub.blocks.assign(block_order_.begin(), block_order_.begin() + lowest_block_count(limits.depth));
  std::sort(sub.blocks.begin(), sub.blocks.end());
  for (const auto& g : genes_) sub.widths[g.group] = g.choices[limit_index(g.choices.size(), limits.width)];
  return sub;
}

int ElasticSpace::lowest_block_count(double depth_limit) const {
  const int total = spec_.blocks, fewest = min_blocks();
  return total - static_cast<int>(std::floor(std::clamp(depth_limit, 0.0, 1.0) * (total - fewest) + 1e-9));
}

SubnetConfig ElasticSpace::sample(std::mt19937_64& rng, ShrinkLimits limits) const {
  SubnetConfig sub;
  for (const auto& g : genes_) {
    const size_t lo = limit_index(g.choices.size(), limits.width);
    std::uniform_int_distribution<size_t> pick(lo, g.choices.size() - 1);
    sub.widths[g.group] = g.choices[pick(rng)];
  }
  const int total = spec_.blocks;
  std::uniform_int_distribution<int> count(lowest_block_count(limits.depth), total);
  const int blocks = count(rng);
  std::vector<int> skippable;
  for (int b = 0; b < total; ++b)
    if (!is_fixed_block(b)) skippable.push_back(b);
  std::shuffle(skippable.begin(), skippable.end(), rng);
  sub.blocks = fixed_blocks_;
  sub.blocks.insert(sub.blocks.end(), skippable.begin(), skippable.begin() + (blocks - static_cast<int>(fixed_blocks_.size())));
  std::sort(sub.blocks.begin(), sub.blocks.end());
  return sub;
}

SubnetConfig ElasticSpace::sample_candidate(std::mt19937_64& rng) const {
  SubnetConfig sub = sample(rng);
  if (options_.precisions.size() > 1) {
    std::uniform_int_distribution<size_t> pick(0, options_.precisions.size() - 1);
    sub.precision = options_.precisions[pick(rng)];
  }
  return sub;
}

bool ElasticSpace::contains(const SubnetConfig& sub) const {
  if (!subnet_problems(spec_, sub).empty()) return false;
  if (static_cast<int>(sub.blocks.size()) < min_blocks()) return false;
  for (int b : fixed_blocks_)
    if (std::find(sub.blocks.begin(), sub.blocks.end(), b) == sub.blocks.end()) return false;
  if (std::find(options_.precisions.begin(), options_.precisions.end(), sub.precision) == options_.precisions.end())
    return false;
  for (const auto& g : genes_) {
    const int64_t w = subnet_width(sub, g.group, g.full);
    if (std::find(g.choices.begin(), g.choices.end(), w) == g.choices.end()) return false;
  }
  return true;
}

SubnetConfig ElasticSpace::repair(SubnetConfig sub) const {
  for (const auto& g : genes_) {
    const int64_t w = subnet_width(sub, g.group, g.full);
    int64_t best = g.choices.front();
    for (int64_t c : g.choices)
      if (std::abs(c - w) < std::abs(best - w) || (std::abs(c - w) == std::abs(best - w) && c > best)) best = c;
    sub.widths[g.group] = best;
  }
  std::vector<int> blocks = fixed_blocks_;
  for (int b : sub.blocks)
    if (b >= 0 && b < spec_.blocks && std::find(blocks.begin(), blocks.end(), b) == blocks.end()) blocks.push_back(b);
  for (int b : block_order_) {
    if (static_cast<int>(blocks.size()) >= min_blocks()) break;
    if (std::find(blocks.begin(), blocks.end(), b) == blocks.end()) blocks.push_back(b);
  }
  std::sort(blocks.begin(), blocks.end());
  sub.blocks = blocks;
  if (std::find(options_.precisions.begin(), options_.precisions.end(), sub.precision) == options_.precisions.end())
    sub.precision = options_.precisions.front();
  return sub;
}

ElasticNetwork make_elastic(const SRNetworkImpl& net, const ElasticOptions& options) {
  return make_elastic(net, options, channel_importance(net));
}

ElasticNetwork make_elastic(const SRNetworkImpl& net, const ElasticOptions& options,
                            const std::map<std::string, torch::Tensor>& importance) {
  std::map<std::string, std::vector<int64_t>> order;
  for (const auto& [group, scores] : importance) {
    const auto s = scores.detach().to(torch::kDouble).contiguous();
    const double* p = s.data_ptr<double>();
    std::vector<int64_t> idx(s.numel());
    std::iota(idx.begin(), idx.end(), 0);
    std::stable_sort(idx.begin(), idx.end(), [p](int64_t a, int64_t b) { return p[a] > p[b]; });
    order[group] = std::move(idx);
  }
  Inheritance sorted = inherit(net, net.spec(), order);
  sorted.network->train(net.is_training());
  std::vector<int> blocks = block_drop_order(net);
  std::reverse(blocks.begin(), blocks.end());
  return {sorted.network, ElasticSpace(net.spec(), options, blocks)};
}

nlohmann::ordered_json elastic_metadata(const ElasticSpace& space) {
  return {{"options", space.options()}, {"block_order", space.block_order()}};
}

ElasticSpace elastic_space_from(const ArchSpec& spec, const nlohmann::ordered_json& extra, const std::string& context) {
  if (!extra.is_object() || !extra.contains("elastic"))
    throw Error(context, "not an elastic network (no 'elastic' record in its provenance; train one with cgsr elastic)");
  try {
    const auto& e = extra.at("elastic");
    return ElasticSpace(spec, e.at("options").get<ElasticOptions>(), e.at("block_order").get<std::vector<int>>());
  } catch (const nlohmann::json::exception& e) {
    throw Error(context, std::string("malformed elastic record: ") + e.what());
  }
}

}  // namespace cgsr
