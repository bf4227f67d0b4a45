#pragma once
// How much each channel of some layer groups matters for one input (a training frame): the
// per-frame ranking that orders the channels of the pattern pool (pruning/pattern_pool.h), whose
// units (pruning/prunable_units.h) name the groups.
//
//   taylor      |sum over the values carrying c (as convolution inputs) of sum_pixels a * dL/da|:
//               the first-order change of the reconstruction loss L (mean squared error to the
//               HR frame) when channel c is removed from the frame (Molchanov et al. 2017)
//   activation  mean |a| of the channel over those values and pixels (no backward pass)

#include <string>
#include <vector>

#include "models/graph.h"
#include "models/importance/channel_importance.h"
#include "models/sr_network.h"
#include "render_data/batch.h"

namespace cgsr {

// What is scored per activation: a * dL/da (Taylor) or |a|.
enum class ActivationScore { Taylor, MeanAbsolute };

// For every one of `groups`: importance [width] (CPU float) under the batch (summed over items).
// The registry in importance_methods.h is the interface the pruner uses.
FrameImportance frame_importance(SRNetworkImpl& net, const Batch& batch, const std::vector<std::string>& groups,
                                 ActivationScore score);

// Op indices whose outputs feed a convolution and carry channels of `groups`: the values where
// removing a channel takes effect (masks and importance apply there).
std::vector<size_t> conv_input_producers(const graph::Graph& graph, const std::vector<std::string>& groups);

}  // namespace cgsr
