#pragma once
// Channel importance for pruning, one interface over every method: a self-filling registry
// (core/registry.h) of functions that score each channel of the pruning units under one input.
//
//   taylor      first-order change of the reconstruction loss when the channel is removed from
//               the frame (activation_importance.h)
//   activation  mean |activation| of the channel on the frame (activation_importance.h)
//   magnitude   L1 norm of the weights producing the channel (SRNetworkImpl::channel_importance):
//               the same for every frame
//
//   const auto& method = importance_methods().get("taylor");
//   FrameImportance scores = method.score(net, batch, units);

#include <functional>
#include <string>
#include <vector>

#include "core/registry.h"
#include "models/sr_network.h"
#include "pruning/pattern_pool.h"
#include "pruning/prunable_units.h"
#include "render_data/batch.h"

namespace cgsr {

struct ImportanceMethod {
  // For every group of `units`: importance [width] (CPU float, larger = keep) under the batch.
  std::function<FrameImportance(SRNetworkImpl&, const Batch&, const std::vector<PrunableUnit>&)> score;
  bool same_on_every_frame = false;  // one frame ranks the channels
  std::string baseline_name;         // the paper's name of pruning by this method ("" = "<name> pruning")
};

const Registry<ImportanceMethod>& importance_methods();

// The `magnitude` method, which needs no frame.
FrameImportance magnitude_importance(const SRNetworkImpl& net, const std::vector<PrunableUnit>& units);

}  // namespace cgsr
