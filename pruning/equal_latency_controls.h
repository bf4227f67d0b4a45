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
// "the leading channels" are the largest. The rate is found for a cost, which the pipeline
// measures as latency against the final network's (pipeline/controls_stage.cpp), so a control
// runs as fast as the network it is compared with.
//
//   ControlNetwork mmp = control_at_latency(*enhanced, ControlKind::Magnitude, 1.0, fraction_of_final);

#include <functional>
#include <string>
#include <vector>

#include "core/enum_names.h"
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

// What a control's rate is matched on: a cost of the network that grows with width.
using NetworkCost = std::function<double(const SRNetwork&)>;

struct ControlNetwork {
  SRNetwork network{nullptr};  // standalone, the geometry head dropped
  double rate = 1;
  double cost = 0;             // as the matching measured it
};

// The largest rate whose control costs at most `target` (bisection, `steps` halvings); the
// smallest rate when none does.
ControlNetwork control_at_latency(const SRNetworkImpl& net, ControlKind kind, double target, const NetworkCost& cost,
                                  int steps = 6);

// The control at a given rate, with its cost.
ControlNetwork control_at_rate(const SRNetworkImpl& net, ControlKind kind, double rate, const NetworkCost& cost);

}  // namespace cgsr
