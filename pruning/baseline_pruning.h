#pragma once
// Static pruning baselines, the controls of hybrid pruning: every group of every pruning unit
// keeps, at one keep rate, its kept_count(width, keep_rate) channels of highest importance under
// one method of the registry (models/importance/importance_methods.h), ranked over the training
// frames. The geometry head is dropped, as in static pruning. `magnitude` is the paper's MMP (Fig. 6(b); structured L1
// pruning, Li et al. 2016). The hybrid model is compared with each at the same MACs (the mean
// its frames execute), fine-tuned with the same number of steps.
//
//   baselines: [{type: magnitude}, {type: taylor, keep_rate: 0.5}]

#include <string>

#include "core/config.h"
#include "models/inherit.h"
#include "models/sr_network.h"
#include "models/channel_selection.h"
#include "pruning/prunable_units.h"

namespace cgsr {

struct BaselineOptions {
  std::string type = "magnitude";  // an importance method (models/importance/importance_methods.h)
  double keep_rate = 0;            // 0: the rate whose MACs match the hybrid model's mean
};
config::Schema<BaselineOptions> baseline_schema();

// "MMP" for magnitude (the paper's name), else "<type> pruning"; the keep rate follows when set.
std::string baseline_label(const BaselineOptions& options);

// Every unit group of `net` keeps the first kept_count(width, keep_rate) channels of `order`
// (per group, channel indices by decreasing importance), in their original order.
Inheritance prune_to_rate(const SRNetworkImpl& net, const ChannelSelection& order, double keep_rate);

// L1-magnitude pruning at `keep_rate` (prune_to_rate with the magnitude order).
Inheritance magnitude_prune(const SRNetworkImpl& net, double keep_rate);

// The largest keep rate whose pruned network costs at most `macs` at the given LR size (the
// smallest rate that keeps a channel per group when none does).
double keep_rate_for_macs(const SRNetworkImpl& net, int64_t macs, int64_t lr_width, int64_t lr_height);

}  // namespace cgsr
