#pragma once
// The magnitude pruning baseline (MMP in Fig. 6(b) of the paper): structured L1-magnitude
// channel pruning (Li et al. 2016). Every group of every pruning unit keeps its
// kept_count(width, keep_rate) channels whose producing weights have the largest L1 norm
// (SRNetworkImpl::channel_importance). The geometry head is dropped, as in static pruning. The
// hybrid model is compared with it at the same MACs (the mean its frames execute), fine-tuned
// with the same number of steps.

#include "models/inherit.h"
#include "models/sr_network.h"
#include "pruning/prunable_units.h"

namespace cgsr {

Inheritance magnitude_prune(const SRNetworkImpl& net, double keep_rate);

// The largest keep rate whose pruned network costs at most `macs` at the given LR size (the
// smallest rate that keeps a channel per group when none does).
double magnitude_rate_for_macs(const SRNetworkImpl& net, int64_t macs, int64_t lr_width, int64_t lr_height);

}  // namespace cgsr
