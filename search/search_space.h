#pragma once
// What the architecture search may change in a parent spec, and the genetic operators on specs.
//
// Genes: the width of every layer group, the number of blocks, the RIT's rendering channels and
// its width. Widths are multiples of a quantum (default 8: odd widths run slowly in every
// runtime) between min_width_fraction x the parent's width and the parent's width; the parent's
// own width is always allowed (PAN's 20 and 24 are not multiples of 8). A candidate is never
// wider or deeper than its parent, because its weights are inherited from the parent.

#include <random>
#include <string>
#include <vector>

#include "core/config.h"
#include "models/arch_spec.h"

namespace cgsr {

struct SearchSpaceOptions {
  int quantum = 8;
  double min_width_fraction = 0.25;
  int min_blocks = 1;
  bool search_blocks = true;
  bool search_rit_channels = true;
  bool search_rit_width = true;
};
config::Schema<SearchSpaceOptions> search_space_schema();

class SearchSpace {
 public:
  SearchSpace(ArchSpec parent, SearchSpaceOptions options);

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

  // A canonical text of the spec: equal specs give equal keys.
  static std::string key(const ArchSpec& spec);

 private:
  // Sets the block count, dropping or restoring (from the parent) the per-block groups.
  ArchSpec with_blocks(const ArchSpec& spec, int blocks) const;
  int min_blocks() const;

  ArchSpec parent_;
  SearchSpaceOptions options_;
};

}  // namespace cgsr
