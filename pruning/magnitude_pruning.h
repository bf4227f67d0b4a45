#pragma once
// The magnitude pruning baseline (MMP in Fig. 6(b) of the paper): structured L1-magnitude
// channel pruning (Li et al. 2016). Every group of every pruning unit keeps its
// kept_count(width, keep_rate) channels whose producing weights have the largest L1 norm
// (SRNetworkImpl::channel_importance), the same channel counts a dynamic pattern keeps, so the
// baseline costs what the hybrid model executes per frame. The geometry head is dropped, as in
// static pruning. The result is fine-tuned like the hybrid model (same budget) for comparison.

#include "models/inherit.h"
#include "models/sr_network.h"
#include "pruning/prunable_units.h"

namespace cgsr {

Inheritance magnitude_prune(const SRNetworkImpl& net, double keep_rate);

}  // namespace cgsr
