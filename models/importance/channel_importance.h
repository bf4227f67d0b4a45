#pragma once
// The magnitude criterion: how much each channel of every prunable layer group matters by the
// weights that produce it, the L1 norm of those weights (and biases), differentiable. A weight
// statistic: it needs no data, and every caller computes the same ranking. Pixel-shuffle groups
// sum their r*r sub-channels.
//
// Users: inheritance keeps a narrower child's most important channels (models/inherit.h), the
// CGSR loss can fade channels before they are cut (train/losses.h: sum ||S_k||), and
// an elastic network sorts its channels by it (models/elastic.h make_elastic, which takes any
// criterion's scores; docs/extending.md adds one), so the magnitude-pruning control
// (pruning/equal_latency_controls.h) keeps the channels it ranks first.
//
//   auto imp = channel_importance(*net);                                    // group -> [width]
//   loss += lambda_s * imp.at("block3_a").index_select(0, shrink).sum();   // sum ||S_k||

#include <torch/types.h>

#include <map>
#include <string>

#include "models/graph.h"
#include "models/sr_network.h"

namespace cgsr {

// Per layer group: channel importance [width] (the criteria of this folder all score this way).
using FrameImportance = std::map<std::string, torch::Tensor>;

// Adds scores of the channel positions of a graph value with `layout` ([layout_width]) to the
// prunable groups they belong to: a group's channel sums its positions (the r*r positions of a
// pixel-shuffle group) and every value the group appears in. How a criterion turns per-op scores
// into per-group ones (docs/extending.md).
void add_position_scores(FrameImportance& importance, const graph::Layout& layout, const torch::Tensor& per_position);

// Importance of each channel of every prunable group produced in `graph`.
std::map<std::string, torch::Tensor> channel_importance(const graph::Graph& graph);
// The same for the network's inference graph (backbone groups and "rit"; no geometry head).
std::map<std::string, torch::Tensor> channel_importance(const SRNetworkImpl& net);

}  // namespace cgsr
