#pragma once
// The controls a compressed network is measured against at equal latency: the CG-enhanced
// network narrowed by weight magnitude, fine-tuned afterwards like the network itself.
//
//   magnitude  every group of every pruning unit (prunable_units.h) keeps its channels of largest
//              L1 norm at one rate; the residual stream and the upsampler stay whole (the paper's
//              MMP, structured L1 pruning)
//   uniform    every layer group (residual stream, upsampler and RIT included) keeps the same
//              fraction: the network scaled uniformly in width
//
// Both are subnets (models/subnet.h) of the network with its channels sorted by magnitude, so
// "the leading channels" are the largest. The rate is found for a latency measured on the
// fused path, so a control runs as fast as the network it is compared with.
//
//   ControlNetwork mmp = control_at_latency(*enhanced, ControlKind::Magnitude, final_ms, measured_latency(320, 240));

#include <functional>
#include <string>
#include <vector>

#include "core/enum_names.h"
#include "models/graph.h"
#include "models/sr_network.h"
#include "models/subnet.h"

namespace cgsr {

enum class ControlKind { Magnitude, Uniform };
template <>
struct EnumNames<ControlKind> {
  static constexpr const char* kind = "control";
  static const std::vector<std::string>& names();  // magnitude, uniform
};

// "MMP" (the paper's name) or "uniform width".
std::string control_label(ControlKind kind);

// The subnet of `net` (its channels sorted by magnitude) that keeps `rate` of the chosen groups.
SubnetConfig control_subnet(const SRNetworkImpl& net, ControlKind kind, double rate);

// What a control's rate is matched on: a cost of its inference graph that grows with width.
using GraphCost = std::function<double(const graph::Graph&)>;
// The fused path's median latency (ms) at an LR size: the cost the pipeline matches on.
GraphCost measured_latency(int64_t lr_width, int64_t lr_height, int runs = 5);

struct ControlNetwork {
  SRNetwork network{nullptr};  // standalone, the geometry head dropped
  double rate = 1;
  double latency_ms = 0;       // its cost, as the matching measured it
};

// The largest rate whose control costs at most `latency_ms` (bisection, `steps` halvings); the
// smallest rate when none does.
ControlNetwork control_at_latency(const SRNetworkImpl& net, ControlKind kind, double latency_ms, const GraphCost& cost,
                                  int steps = 6);

// The control at a given rate, with its cost.
ControlNetwork control_at_rate(const SRNetworkImpl& net, ControlKind kind, double rate, const GraphCost& cost);

}  // namespace cgsr
