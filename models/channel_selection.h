#pragma once
// Which channels of each prunable layer group remain, and the network graph that computes with
// only those: the structured form every pruning step here shares. A selection narrows whole
// channels, so the result runs as smaller dense convolutions (no masks, no sparse kernels).
//
//   ChannelSelection keep = {{"block3_a", {0, 4, 7}}, ...};
//   graph::Graph small = select_channels(net->describe(), keep);   // weights gathered (copies)
//   graph::run(small, inputs);
//
// Removing a channel removes it from every value it appears in: the rows of the layers writing
// it and the columns of the layers reading it, both operands of a product, all r*r positions
// of a pixel-shuffle group (graph.h layouts). Because the selection is per group, residual
// additions stay consistent.

#include <map>
#include <string>
#include <vector>

#include "models/graph.h"

namespace cgsr {

// Layer group -> kept channel indices (strictly increasing). Groups not listed keep every channel.
using ChannelSelection = std::map<std::string, std::vector<int64_t>>;

// Positions along an axis with `layout` that remain under `keep`, in order.
std::vector<int64_t> selected_positions(const graph::Layout& layout, const ChannelSelection& keep);
// The layout of those positions.
graph::Layout selected_layout(const graph::Layout& layout, const ChannelSelection& keep);

// Checks `keep` against the groups of `graph` (known, prunable, increasing, in range, non-empty);
// throws cgsr::Error naming the group otherwise.
void check_selection(const graph::Graph& graph, const ChannelSelection& keep, const std::string& context);

// The graph restricted to the selection: Conv and ChannelAffine tensors are gathered copies, or
// views where the kept positions are a leading run (the first channels of a group), every value's
// layout narrowed. Ops and values keep their indices and names. With `differentiable` the
// narrowing is recorded by autograd (under the caller's grad mode), so a loss of the narrowed
// graph reaches the original tensors: how subnets of an elastic network train (models/subnet.h).
graph::Graph select_channels(const graph::Graph& graph, const ChannelSelection& keep, bool differentiable = false);

// The gathered tensors of one op under a selection (what select_channels puts into the op).
struct SelectedTensors {
  torch::Tensor weight, bias, scale, shift;
};
SelectedTensors select_op_tensors(const graph::Graph& graph, const graph::Op& op, const ChannelSelection& keep);

// Widths of every prunable group appearing in the graph, in order of first appearance.
std::vector<std::pair<std::string, int64_t>> group_widths(const graph::Graph& graph);

}  // namespace cgsr
