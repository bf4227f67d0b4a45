#pragma once
// What the architecture search may change in a parent spec, and the genetic operators on specs.
//
// Genes: the width of every layer group, the number of blocks, the RIT's rendering channels and
// its width. Widths are multiples of a quantum (default 8: odd widths run slowly in every
// runtime) between min_width_fraction x the parent's width and the parent's width; the parent's
// own width is always allowed (PAN's 20 and 24 are not multiples of 8). A candidate is never
// wider or deeper than its parent, because its weights are inherited from the parent.
//
// A candidate with fewer blocks keeps the parent blocks a drop order spares
// (models/importance/block_importance.h: the least important go first), and its block genes are those of
// the parent blocks it keeps: block i of a candidate is parent block parent_blocks(spec)[i].

#include <map>
#include <random>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/enum_names.h"
#include "models/arch_spec.h"

namespace cgsr {

enum class BlockDrop { Importance, Trailing };
template <>
struct EnumNames<BlockDrop> {
  static constexpr const char* kind = "block drop";
  static const std::vector<std::string>& names();  // importance, trailing
};

struct SearchSpaceOptions {
  int quantum = 8;
  double min_width_fraction = 0.25;
  int min_blocks = 1;
  bool search_blocks = true;
  bool search_rit_channels = true;
  bool search_rit_width = true;
  // Which blocks a shallower candidate drops: the parent's least important, or its last ones.
  BlockDrop drop_blocks = BlockDrop::Importance;
};
config::Schema<SearchSpaceOptions> search_space_schema();

class SearchSpace {
 public:
  // `drop_order`: the parent's blocks, least important first (block_drop_order); empty, or
  // options.drop_blocks trailing: the last block first.
  SearchSpace(ArchSpec parent, SearchSpaceOptions options, std::vector<int> drop_order = {});

  const ArchSpec& parent() const { return parent_; }

  // Allowed widths of a group (ascending), from its width in the parent.
  std::vector<int> width_choices(int parent_width) const;

  // Changes each gene with probability `rate`, mostly by one step, and repairs the result.
  ArchSpec mutate(const ArchSpec& spec, double rate, std::mt19937_64& rng) const;
  // Takes each gene from `a` or `b` with equal probability.
  ArchSpec crossover(const ArchSpec& a, const ArchSpec& b, std::mt19937_64& rng) const;
  // Every gene drawn uniformly from its choices (the random-search baseline).
  ArchSpec sample(std::mt19937_64& rng) const;

  // Whether the spec lies in the space and builds (valid widths, inheritable from the parent).
  bool contains(const ArchSpec& spec) const;

  // The parent block each of the spec's blocks inherits (ascending; models/inherit.h).
  std::vector<int> parent_blocks(const ArchSpec& spec) const;

  // A canonical text of the spec: equal specs give equal keys.
  static std::string key(const ArchSpec& spec);

 private:
  // Sets the block count, dropping or restoring (from the parent) the per-block groups.
  ArchSpec with_blocks(const ArchSpec& spec, int blocks) const;
  int min_blocks() const;

  // The parent's name of one of the spec's layer groups (a block group: its parent block's).
  std::string parent_group(const ArchSpec& spec, const std::string& group) const;
  int parent_width(const ArchSpec& spec, const std::string& group) const;
  // The spec's block-group widths under their parent names ("block<p>_<suffix>" -> width, for
  // the parent blocks p the spec keeps).
  std::map<std::string, int> block_genes(const ArchSpec& spec) const;

  ArchSpec parent_;
  SearchSpaceOptions options_;
  std::vector<int> drop_order_;
};

}  // namespace cgsr
