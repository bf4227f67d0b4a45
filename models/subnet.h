#pragma once
// A subnet of a network: the residual blocks it keeps and how many channels of each layer group
// it keeps, always the leading ones. This is the one way the code base narrows a network: an
// elastic network's subnets (elastic.h), the search's candidates and the dynamic pruning's
// patterns are all subnets of one full network.
//
//   SubnetConfig sub{{0, 2, 3}, {{"features", 32}, {"block0_a", 12}}};
//   graph::Graph g = subnet_graph(*net, sub);             // views of the full network's weights
//   SRNetwork small = materialize_subnet(*net, sub);      // a standalone network (copies)
//
// "The leading channels" mean something because an elastic network's channels are sorted by
// importance once (channel 0 of a group matters most). Block indices and group names are the
// full network's: a subnet keeping blocks {0, 3} still calls its groups block3_a, ...; its
// standalone spec (subnet_spec) numbers them 0, 1 like any network.
//
// Skipping a residual block passes its input on unchanged (the block's output is input + branch,
// so a skipped block is one whose branch is zero); a subnet's graph equals the full graph with
// the skipped blocks' branches and the dropped channels masked to zero.

#include <torch/types.h>

#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "models/arch_spec.h"
#include "models/channel_selection.h"
#include "models/graph.h"
#include "models/precision.h"
#include "models/sr_network.h"

namespace cgsr {

struct SubnetConfig {
  std::vector<int> blocks;                // kept blocks of the full network, ascending
  std::map<std::string, int64_t> widths;  // layer group -> leading channels kept; absent: all
  Precision precision = Precision::Fp32;  // the format it runs in (the search's choice, precision.h);
                                          // the graph and the weights do not depend on it

  bool operator==(const SubnetConfig& o) const {
    return blocks == o.blocks && widths == o.widths && precision == o.precision;
  }
  bool operator!=(const SubnetConfig& o) const { return !(*this == o); }
};

// Every layer group of a (resolved) spec with its full width, in order: the backbone's, then the RIT's.
std::vector<std::pair<std::string, int64_t>> layer_groups(const ArchSpec& spec);

// Every block and every channel of a (resolved) spec: the full network as a subnet.
SubnetConfig full_subnet(const ArchSpec& spec);

// The channels a subnet keeps of `group` in a network where the group is `full_width` wide.
int64_t subnet_width(const SubnetConfig& sub, const std::string& group, int64_t full_width);

// A canonical text: subnets that compute the same give equal keys ("b=0,2,3|features=32|...",
// then "|int8" when not float32); the widths of skipped blocks do not count.
std::string subnet_key(const SubnetConfig& sub);

nlohmann::ordered_json to_json(const SubnetConfig& sub);
// Errors name `context` and the offending key.
SubnetConfig subnet_from_json(const nlohmann::ordered_json& j, const std::string& context);

// The subnet's problems in a network of `spec` (empty when it is a subnet of it): block indices
// in range and ascending, known groups, widths in [1, full width].
std::vector<std::string> subnet_problems(const ArchSpec& spec, const SubnetConfig& sub);

// The graph without the ops of the blocks not in `kept` (blocks of the backbone named
// "backbone.blocks.<i>." in the graph): every reader of a skipped block's output reads its input
// instead. Values are renumbered; op names stay.
graph::Graph skip_blocks(const graph::Graph& graph, const std::vector<int>& kept, int total_blocks);

// The prefix selection of a subnet over the groups present in `graph`.
ChannelSelection subnet_selection(const graph::Graph& graph, const SubnetConfig& sub);

// The subnet's graph over `net`'s tensors: leading slices are views (only an axis that
// concatenates groups, such as PAN's conv3 input, is gathered). With `differentiable`, a loss of
// its output reaches `net`'s parameters (training subnets in place); `training` includes the
// geometry head, which always keeps every channel of its own group.
graph::Graph subnet_graph(const SRNetworkImpl& net, const SubnetConfig& sub, bool training = false,
                          bool differentiable = false);

// The spec of the subnet as a network of its own: blocks renumbered, widths of what it keeps,
// the RIT's widths from its groups.
ArchSpec subnet_spec(const ArchSpec& full, const SubnetConfig& sub);

// The subnet as a standalone network with copies of its weights: it computes what subnet_graph
// computes, and trains, saves and exports like any network. The geometry head (training only)
// comes along unless `geometry_head` is false.
SRNetwork materialize_subnet(const SRNetworkImpl& net, const SubnetConfig& sub, bool geometry_head = true);

}  // namespace cgsr
