#pragma once
// Channel importance, one interface over every criterion: a self-filling registry
// (core/registry.h) of functions that score each channel of some layer groups (for pruning, the
// groups of its units: pruning/prunable_units.h) under one input.
//
//   taylor      first-order change of the reconstruction loss when the channel is removed from
//               the frame (activation_importance.h)
//   activation  mean |activation| of the channel on the frame (activation_importance.h)
//   magnitude   L1 norm of the weights producing the channel (channel_importance.h): the same
//               for every frame
//
// Block importance (block_importance.h), which residual blocks a shallower network drops, is the
// other criterion of this folder.
//
//   const auto& method = importance_methods().get("taylor");
//   FrameImportance scores = method.score(net, batch, unit_groups(units));

#include <functional>
#include <string>
#include <vector>

#include "core/registry.h"
#include "models/importance/channel_importance.h"
#include "models/sr_network.h"
#include "render_data/batch.h"

namespace cgsr {

struct ImportanceMethod {
  // For every one of the groups: importance [width] (CPU float, larger = keep) under the batch.
  std::function<FrameImportance(SRNetworkImpl&, const Batch&, const std::vector<std::string>&)> score;
  bool same_on_every_frame = false;  // one frame ranks the channels
  std::string baseline_name;         // the paper's name of pruning by this method ("" = "<name> pruning")
};

const Registry<ImportanceMethod>& importance_methods();

// The `magnitude` method, which needs no frame.
FrameImportance magnitude_importance(const SRNetworkImpl& net, const std::vector<std::string>& groups);

}  // namespace cgsr
