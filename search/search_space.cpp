#include "search/search_space.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "core/error.h"
#include "models/backbone_registry.h"
#include "models/importance/block_importance.h"
#include "models/inherit.h"

namespace cgsr {

const std::vector<std::string>& EnumNames<BlockDrop>::names() {
  static const std::vector<std::string> n{"importance", "trailing"};
  return n;
}

config::Schema<SearchSpaceOptions> search_space_schema() {
  config::Schema<SearchSpaceOptions> s;
  s.field("quantum", &SearchSpaceOptions::quantum, "widths are multiples of this").range(1, 256);
  s.field("min_width_fraction", &SearchSpaceOptions::min_width_fraction, "narrowest width relative to the parent")
      .range(0.0, 1.0);
  s.field("min_blocks", &SearchSpaceOptions::min_blocks, "fewest residual blocks").at_least(0);
  s.field("search_blocks", &SearchSpaceOptions::search_blocks, "vary the number of blocks");
  s.field("search_rit_channels", &SearchSpaceOptions::search_rit_channels, "vary the RIT's rendering channels");
  s.field("search_rit_width", &SearchSpaceOptions::search_rit_width, "vary the RIT's width");
  s.field("drop_blocks", &SearchSpaceOptions::drop_blocks,
          "blocks a shallower candidate drops: the parent's least important, or its last ones");
  return s;
}

SearchSpace::SearchSpace(ArchSpec parent, SearchSpaceOptions options, std::vector<int> drop_order)
    : parent_(resolve_spec(std::move(parent))), options_(options), drop_order_(std::move(drop_order)) {
  const int blocks = std::max(0, parent_.blocks);
  if (options_.drop_blocks == BlockDrop::Trailing || drop_order_.empty()) {
    drop_order_.clear();
    for (int b = blocks - 1; b >= 0; --b) drop_order_.push_back(b);
  }
  std::vector<int> sorted = drop_order_;
  std::sort(sorted.begin(), sorted.end());
  for (int b = 0; b < static_cast<int>(sorted.size()); ++b)
    CGSR_CHECK(sorted[b] == b && static_cast<int>(sorted.size()) == blocks,
               "SearchSpace: the block drop order must list each of the parent's " + std::to_string(blocks) +
                   " blocks once");
}

std::vector<int> SearchSpace::parent_blocks(const ArchSpec& spec) const {
  return kept_blocks(drop_order_, std::max(0, resolve_spec(spec).blocks));
}

std::string SearchSpace::parent_group(const ArchSpec& spec, const std::string& group) const {
  const auto block = parse_block_group(group);
  return block ? block_group(parent_blocks(spec).at(block->first), block->second) : group;
}

int SearchSpace::parent_width(const ArchSpec& spec, const std::string& group) const {
  return parent_.widths.at(parent_group(spec, group));
}

std::map<std::string, int> SearchSpace::block_genes(const ArchSpec& spec) const {
  std::map<std::string, int> genes;
  const auto kept = parent_blocks(spec);
  for (const auto& [group, width] : spec.widths.entries())
    if (const auto block = parse_block_group(group); block && block->first < static_cast<int>(kept.size()))
      genes[block_group(kept[block->first], block->second)] = width;
  return genes;
}

std::vector<int> SearchSpace::width_choices(int parent_width) const {
  const int lowest = std::max(1, static_cast<int>(std::ceil(options_.min_width_fraction * parent_width)));
  std::vector<int> out;
  for (int w = options_.quantum; w < parent_width; w += options_.quantum)
    if (w >= lowest) out.push_back(w);
  out.push_back(parent_width);
  return out;
}

int SearchSpace::min_blocks() const {
  const int backbone_min = backbone_registry().get(parent_.backbone).min_blocks;
  return std::min(parent_.blocks, std::max(backbone_min, options_.min_blocks));
}

ArchSpec SearchSpace::with_blocks(const ArchSpec& spec, int blocks) const {
  const auto genes = block_genes(spec);
  const auto kept = kept_blocks(drop_order_, blocks);
  ArchSpec out = spec;
  out.blocks = blocks;
  out.widths = GroupWidths();
  const auto& info = backbone_registry().get(parent_.backbone);
  for (const auto& group : info.groups(parent_.scale, blocks)) {
    // A block group of block i takes the gene of the parent block it keeps, or that block's width.
    if (const auto block = parse_block_group(group.name)) {
      const std::string in_parent = block_group(kept.at(block->first), block->second);
      const auto gene = genes.find(in_parent);
      out.widths.set(group.name, gene != genes.end() ? gene->second : parent_.widths.at(in_parent));
    } else {
      out.widths.set(group.name, spec.widths.contains(group.name) ? spec.widths.at(group.name)
                                                                  : parent_.widths.at(group.name));
    }
  }
  return out;
}

namespace {
// One step up or down the choices, or (rarely) a jump anywhere.
int mutate_choice(const std::vector<int>& choices, int current, std::mt19937_64& rng) {
  auto it = std::find(choices.begin(), choices.end(), current);
  const size_t index = it == choices.end() ? choices.size() - 1 : static_cast<size_t>(it - choices.begin());
  std::uniform_real_distribution<double> u(0, 1);
  if (u(rng) < 0.25) return choices[std::uniform_int_distribution<size_t>(0, choices.size() - 1)(rng)];
  const bool down = u(rng) < 0.6;  // shrinking is the point of the search
  if (down && index > 0) return choices[index - 1];
  if (!down && index + 1 < choices.size()) return choices[index + 1];
  return choices[index];
}
}  // namespace

ArchSpec SearchSpace::mutate(const ArchSpec& spec, double rate, std::mt19937_64& rng) const {
  std::uniform_real_distribution<double> u(0, 1);
  ArchSpec out = spec;
  if (options_.search_blocks && parent_.blocks > 0 && u(rng) < rate) {
    std::vector<int> blocks;
    for (int b = min_blocks(); b <= parent_.blocks; ++b) blocks.push_back(b);
    out = with_blocks(out, mutate_choice(blocks, out.blocks, rng));
  }
  GroupWidths widths;
  for (const auto& [group, width] : out.widths.entries())
    widths.set(group, u(rng) < rate ? mutate_choice(width_choices(parent_width(out, group)), width, rng) : width);
  out.widths = widths;
  if (parent_.rit.enabled) {
    if (options_.search_rit_width && u(rng) < rate)
      out.rit.width = mutate_choice(width_choices(parent_.rit.width), out.rit.width, rng);
    if (options_.search_rit_width && parent_.rit.hr_branch() && u(rng) < rate)
      out.rit.hr_width = mutate_choice(width_choices(parent_.rit.hr_width), out.rit.hr_width, rng);
    if (options_.search_rit_channels && u(rng) < rate) {
      // Toggle one of the parent's channels, keeping at least one.
      const auto& all = parent_.rit.channels;
      const std::string pick = all[std::uniform_int_distribution<size_t>(0, all.size() - 1)(rng)];
      auto channels = out.rit.channels;
      auto it = std::find(channels.begin(), channels.end(), pick);
      if (it != channels.end() && channels.size() > 1) channels.erase(it);
      else if (it == channels.end()) channels.push_back(pick);
      out.rit.channels = channel_names(parse_channels(channels));
    }
  }
  return resolve_spec(out);
}

ArchSpec SearchSpace::crossover(const ArchSpec& a, const ArchSpec& b, std::mt19937_64& rng) const {
  std::bernoulli_distribution coin(0.5);
  ArchSpec out = with_blocks(a, coin(rng) ? a.blocks : b.blocks);
  // Block genes cross by the parent block they belong to.
  const auto b_genes = block_genes(b);
  const auto kept = parent_blocks(out);
  GroupWidths widths;
  for (const auto& [group, width] : out.widths.entries()) {
    std::optional<int> from_b;
    if (const auto block = parse_block_group(group)) {
      const auto gene = b_genes.find(block_group(kept.at(block->first), block->second));
      if (gene != b_genes.end()) from_b = gene->second;
    } else if (b.widths.contains(group)) {
      from_b = b.widths.at(group);
    }
    widths.set(group, from_b && coin(rng) ? *from_b : width);
  }
  out.widths = widths;
  if (parent_.rit.enabled) {
    out.rit.width = coin(rng) ? a.rit.width : b.rit.width;
    if (parent_.rit.hr_branch()) out.rit.hr_width = coin(rng) ? a.rit.hr_width : b.rit.hr_width;
    std::vector<std::string> channels;
    for (const auto& c : parent_.rit.channels) {
      const auto& from = coin(rng) ? a.rit.channels : b.rit.channels;
      if (std::find(from.begin(), from.end(), c) != from.end()) channels.push_back(c);
    }
    out.rit.channels = channels.empty() ? a.rit.channels : channels;
  }
  return resolve_spec(out);
}

ArchSpec SearchSpace::sample(std::mt19937_64& rng) const {
  auto any = [&](const std::vector<int>& choices) {
    return choices[std::uniform_int_distribution<size_t>(0, choices.size() - 1)(rng)];
  };
  ArchSpec out = parent_;
  if (options_.search_blocks && parent_.blocks > 0)
    out = with_blocks(out, std::uniform_int_distribution<int>(min_blocks(), parent_.blocks)(rng));
  GroupWidths widths;
  for (const auto& [group, width] : out.widths.entries()) widths.set(group, any(width_choices(parent_width(out, group))));
  out.widths = widths;
  if (parent_.rit.enabled) {
    if (options_.search_rit_width) out.rit.width = any(width_choices(parent_.rit.width));
    if (options_.search_rit_width && parent_.rit.hr_branch()) out.rit.hr_width = any(width_choices(parent_.rit.hr_width));
    if (options_.search_rit_channels) {
      std::vector<std::string> channels;
      std::bernoulli_distribution coin(0.5);
      for (const auto& c : parent_.rit.channels)
        if (coin(rng)) channels.push_back(c);
      if (channels.empty()) channels.push_back(parent_.rit.channels[std::uniform_int_distribution<size_t>(
          0, parent_.rit.channels.size() - 1)(rng)]);
      out.rit.channels = channels;
    }
  }
  return resolve_spec(out);
}

bool SearchSpace::contains(const ArchSpec& spec) const {
  try {
    validate_spec(spec);
  } catch (const Error&) {
    return false;
  }
  if (spec.blocks > parent_.blocks || !inheritance_problems(parent_, spec, parent_blocks(spec)).empty()) return false;
  for (const auto& [group, width] : spec.widths.entries()) {
    const std::string in_parent = parent_group(spec, group);
    if (!parent_.widths.contains(in_parent)) return false;
    const auto choices = width_choices(parent_.widths.at(in_parent));
    if (std::find(choices.begin(), choices.end(), width) == choices.end()) return false;
  }
  return true;
}

std::string SearchSpace::key(const ArchSpec& spec) { return spec_to_yaml(spec); }

}  // namespace cgsr
