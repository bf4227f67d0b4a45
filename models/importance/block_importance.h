#pragma once
// Which residual blocks of a backbone matter least, so that a shallower child drops those and not
// simply the trailing ones (the search's block gene; CGSR "Layer-wise pruning").
//
// A block reads the residual stream and adds its branch back into it. Its importance is the L1
// norm of the weights of its ops whose output lies on the stream (PAN's conv3, EDSR's conv2):
// a block that writes little changes the stream little. A weight statistic, like the channel
// importance of channel_importance.h, so it needs no data and every caller computes the same order.
//
//   auto order = block_drop_order(*parent);     // parent blocks, least important first
//   auto kept = kept_blocks(order, 12);          // the 12 a 12-block child keeps, ascending
//   inherit(*parent, child_spec, {}, kept);      // child block i <- parent block kept[i]

#include <vector>

#include "models/sr_network.h"

namespace cgsr {

// One value per block of the network's backbone (empty for a backbone without blocks).
std::vector<double> block_importance(const SRNetworkImpl& network);

// The network's blocks from least to most important (ties: the later block first, so equal
// importance drops trailing blocks as a shallower network always did).
std::vector<int> block_drop_order(const SRNetworkImpl& network);

// The blocks a child with `blocks` blocks keeps, in ascending order: all but the first
// (drop_order.size() - blocks) of `drop_order`. Nested: fewer blocks keep a subset.
std::vector<int> kept_blocks(const std::vector<int>& drop_order, int blocks);

}  // namespace cgsr
