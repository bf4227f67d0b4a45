#pragma once
// Weight inheritance: builds a child spec's network from a trained parent (CGSR's warm start).
//
// Per layer group, the child keeps the parent channels of largest importance (L1 norm of the
// weights producing them, importance/channel_importance.h), in their original order, and copies
// every tensor through the graph layouts: a channel removed from a residual stream is removed
// from every layer writing into or reading from it, both operands of an attention product lose
// the same channels, and a pixel-shuffle group keeps or drops all r*r sub-channels together.
// Block i of the child inherits block i of the parent (a child may have fewer blocks), or the
// parent block the caller names (a subnet's kept blocks, subnet.h).
//
// Parts the parent lacks start fresh: a RIT (its fusion is zero, so the output equals the
// parent's exactly) and the geometry head. The child's RIT may read a subset of the parent's
// rendering channels. A child identical to its parent computes bit-identical outputs.
//
// The child must keep the parent's backbone, scale, colours and RIT source/fusion, and may not
// be wider or deeper than the parent: there are no trained weights to copy.

#include <map>
#include <string>
#include <vector>

#include "models/arch_spec.h"
#include "models/sr_network.h"

namespace cgsr {

struct Inheritance {
  SRNetwork network{nullptr};
  // The parent's layer group -> its channel indices kept (a child block's groups appear under
  // the name of the parent block it inherits).
  std::map<std::string, std::vector<int64_t>> kept;
  std::vector<std::string> fresh;                    // parameters that start from initialization
};

Inheritance inherit(const SRNetworkImpl& parent, const ArchSpec& child_spec);

// The same with the channels of some groups chosen by the caller (pruning): `kept[group]` lists
// distinct parent channel indices in the child's channel order, as many as the child's width of
// that group (a permutation of a same-width group reorders its channels). Groups not listed are
// chosen by importance as above. `parent_blocks` (ascending, one per child block) names the
// parent block each child block inherits; empty: the first child.blocks blocks, but for the
// backbone's fixed blocks, which are always among them (SPAN's first and last).
Inheritance inherit(const SRNetworkImpl& parent, const ArchSpec& child_spec,
                    const std::map<std::string, std::vector<int64_t>>& kept,
                    const std::vector<int>& parent_blocks = {});

// The child spec's problems with `parent` (empty when inheritance is possible), with child block
// i compared to parent block parent_blocks[i] (empty: as inherit chooses them).
std::vector<std::string> inheritance_problems(const ArchSpec& parent, const ArchSpec& child,
                                              const std::vector<int>& parent_blocks = {});

}  // namespace cgsr
