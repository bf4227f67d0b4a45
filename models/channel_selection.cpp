#include "models/channel_selection.h"

#include <torch/torch.h>

#include <optional>

#include "core/error.h"

namespace cgsr {

namespace {
const std::vector<int64_t>* find_kept(const ChannelSelection& keep, const graph::Segment& s) {
  if (!s.prunable) return nullptr;
  const auto it = keep.find(s.group);
  return it == keep.end() ? nullptr : &it->second;
}

// A leading run of positions 0, 1, ..., n - 1 (nested patterns) is a view; anything else a copy.
torch::Tensor slice_or_gather(const torch::Tensor& t, int64_t dim, const std::vector<int64_t>& index) {
  bool prefix = true;
  for (size_t i = 0; i < index.size() && prefix; ++i) prefix = index[i] == static_cast<int64_t>(i);
  if (prefix) return t.narrow(dim, 0, static_cast<int64_t>(index.size()));
  return t.index_select(dim, torch::tensor(index, torch::kLong)).contiguous();
}

bool narrows(const graph::Layout& layout, const ChannelSelection& keep) {
  for (const auto& s : layout)
    if (const auto* k = find_kept(keep, s); k && static_cast<int64_t>(k->size()) != s.channels) return true;
  return false;
}
}  // namespace

std::vector<int64_t> selected_positions(const graph::Layout& layout, const ChannelSelection& keep) {
  std::vector<int64_t> out;
  int64_t offset = 0;
  for (const auto& s : layout) {
    if (const auto* k = find_kept(keep, s)) {
      for (int64_t c : *k)
        for (int64_t r = 0; r < s.repeat; ++r) out.push_back(offset + c * s.repeat + r);
    } else {
      for (int64_t p = 0; p < s.channels * s.repeat; ++p) out.push_back(offset + p);
    }
    offset += s.channels * s.repeat;
  }
  return out;
}

graph::Layout selected_layout(const graph::Layout& layout, const ChannelSelection& keep) {
  graph::Layout out = layout;
  for (auto& s : out)
    if (const auto* k = find_kept(keep, s)) s.channels = static_cast<int64_t>(k->size());
  return out;
}

std::vector<std::pair<std::string, int64_t>> group_widths(const graph::Graph& graph) {
  std::vector<std::pair<std::string, int64_t>> out;
  for (const auto& v : graph.values)
    for (const auto& s : v.layout) {
      if (!s.prunable) continue;
      bool seen = false;
      for (const auto& [g, w] : out) seen = seen || g == s.group;
      if (!seen) out.emplace_back(s.group, s.channels);
    }
  return out;
}

void check_selection(const graph::Graph& graph, const ChannelSelection& keep, const std::string& context) {
  const auto widths = group_widths(graph);
  for (const auto& [group, channels] : keep) {
    int64_t width = -1;
    for (const auto& [g, w] : widths)
      if (g == group) width = w;
    if (width < 0) throw Error(context, "no prunable layer group '" + group + "' in the network");
    if (channels.empty()) throw Error(context, "layer group " + group + " would keep no channel");
    for (size_t i = 0; i < channels.size(); ++i)
      if (channels[i] < 0 || channels[i] >= width || (i > 0 && channels[i] <= channels[i - 1]))
        throw Error(context, "channels of layer group " + group + " must be increasing indices below " +
                                 std::to_string(width));
  }
}

SelectedTensors select_op_tensors(const graph::Graph& graph, const graph::Op& op, const ChannelSelection& keep) {
  SelectedTensors t{op.weight, op.bias, op.scale, op.shift};
  const auto& out_layout = graph.values[op.output].layout;
  const bool out_narrows = narrows(out_layout, keep);
  if (graph::op_traits(op.kind).mixes_channels) {
    const auto& in_layout = graph.values[op.inputs[0]].layout;
    const bool in_narrows = narrows(in_layout, keep);
    if (!out_narrows && !in_narrows) return t;
    CGSR_CHECK(op.groups == 1, "select_channels: grouped convolution " + op.name + " cannot be narrowed");
    if (out_narrows) {
      const auto rows = selected_positions(out_layout, keep);
      t.weight = slice_or_gather(t.weight, 0, rows);
      if (t.bias.defined()) t.bias = slice_or_gather(t.bias, 0, rows);
    }
    if (in_narrows) t.weight = slice_or_gather(t.weight, 1, selected_positions(in_layout, keep));
  } else if (graph::op_traits(op.kind).has_tensors && out_narrows) {
    const auto positions = selected_positions(out_layout, keep);
    if (t.scale.defined()) t.scale = slice_or_gather(t.scale, 0, positions);
    if (t.shift.defined()) t.shift = slice_or_gather(t.shift, 0, positions);
  }
  return t;
}

graph::Graph select_channels(const graph::Graph& graph, const ChannelSelection& keep, bool differentiable) {
  check_selection(graph, keep, "channel selection");
  std::optional<torch::NoGradGuard> no_grad;
  if (!differentiable) no_grad.emplace();
  graph::Graph out = graph;
  for (auto& op : out.ops) {
    if (!graph::op_traits(op.kind).has_tensors) continue;
    auto t = select_op_tensors(graph, op, keep);
    op.weight = t.weight;
    op.bias = t.bias;
    op.scale = t.scale;
    op.shift = t.shift;
  }
  for (auto& v : out.values) v.layout = selected_layout(v.layout, keep);
  return out;
}

}  // namespace cgsr
