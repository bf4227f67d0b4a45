#pragma once
// The units dynamic pruning works on: sets of layer groups inside a block that may change from
// frame to frame without touching the rest of the network.
//
// A group can be pruned per frame when it never reaches a residual addition (a residual stream
// such as PAN's or EDSR's "features" is shared by every block) or a graph output. Groups tied
// by a convolution (read by it and written by it) are pruned together, so every weight tensor
// belongs to at most one unit and a pattern of a unit can be executed by swapping that unit's
// gathered weights alone. Units are the connected components of that relation:
//   PAN    block<i> = {a, a_out, b, att, b_out}, and the upsampler {up1, hr1 (, up2, hr2)}
//   EDSR   block<i> = {mid}, and the upsampler {up1 (, up2)}
//   SRCNN  {conv1, conv2}
//   RIT    {rit} (the transform's features; its rendering-channel inputs are fixed)

#include <cstdint>
#include <string>
#include <vector>

#include "models/graph.h"

namespace cgsr {

struct PrunableUnit {
  std::string name;                 // "block3" for block groups, else the groups joined by '+'
  std::vector<std::string> groups;  // in order of first appearance in the graph
  std::vector<int64_t> widths;      // channels per group
  std::vector<size_t> ops;          // Conv/ChannelAffine ops whose tensors touch the groups

  int64_t width(const std::string& group) const;  // Error when the group is not in the unit
  int64_t total_width() const;
};

std::vector<PrunableUnit> find_units(const graph::Graph& graph);

// The groups of every unit, unit after unit: what the importance criteria score
// (models/importance/).
std::vector<std::string> unit_groups(const std::vector<PrunableUnit>& units);

// Channels a pattern keeps of a group `width` wide at `keep_rate`: round(rate * width), at least 1.
int64_t kept_count(int64_t width, double keep_rate);

}  // namespace cgsr
