#include "models/complexity.h"

#include <cmath>
#include <cstdio>

#include "models/sr_network.h"

namespace cgsr {

Complexity complexity(const graph::Graph& graph, int64_t lr_width, int64_t lr_height) {
  Complexity c;
  c.lr_width = lr_width;
  c.lr_height = lr_height;
  for (const auto& op : graph.ops) {
    const auto& out = graph.values[op.output];
    LayerCost layer;
    layer.name = op.name;
    layer.kind = graph::op_kind_name(op.kind);
    layer.out_width = lr_width * out.factor;
    layer.out_height = lr_height * out.factor;
    layer.out_channels = graph::layout_width(out.layout);
    layer.trainable = op.trainable;
    const auto traits = graph::op_traits(op.kind);
    if (!traits.has_tensors) continue;
    if (op.trainable) layer.params = graph::tensor_elements(op);
    layer.macs = graph::macs_per_output_pixel(op) * layer.out_width * layer.out_height;
    if (traits.mixes_channels) {
      layer.in_channels = op.weight.size(1) * op.groups;
      layer.kernel = op.kernel_size();
      layer.groups = op.groups;
    } else {
      layer.in_channels = layer.out_channels;
      if (layer.params == 0) continue;  // a constant element-wise op: nothing to count
    }
    c.params += layer.params;
    c.macs += layer.macs;
    c.layers.push_back(layer);
  }
  const auto& image = graph.values[graph.output("image")];
  c.hr_width = lr_width * image.factor;
  c.hr_height = lr_height * image.factor;
  return c;
}

Complexity complexity(const SRNetworkImpl& net, int64_t lr_width, int64_t lr_height) {
  return complexity(net.describe(false), lr_width, lr_height);
}

std::pair<int64_t, int64_t> lr_size_for_output(int64_t hr_width, int64_t hr_height, int scale) {
  return {hr_width / scale, hr_height / scale};
}

std::string format_count(double count) {
  const char* units[] = {"", "K", "M", "G", "T"};
  int u = 0;
  while (std::fabs(count) >= 1000.0 && u < 4) {
    count /= 1000.0;
    ++u;
  }
  char buf[32];
  const int decimals = std::fabs(count) >= 100 ? 1 : std::fabs(count) >= 10 ? 2 : 3;
  std::snprintf(buf, sizeof buf, "%.*f%s", u == 0 ? 0 : decimals, count, units[u]);
  return buf;
}

nlohmann::ordered_json to_json(const Complexity& c) {
  nlohmann::ordered_json j;
  j["input"] = std::to_string(c.lr_width) + "x" + std::to_string(c.lr_height);
  j["output"] = std::to_string(c.hr_width) + "x" + std::to_string(c.hr_height);
  j["params"] = c.params;
  j["macs"] = c.macs;
  j["macs_g"] = static_cast<double>(c.macs) / 1e9;
  auto layers = nlohmann::ordered_json::array();
  for (const auto& l : c.layers) {
    nlohmann::ordered_json x;
    x["name"] = l.name;
    x["kind"] = l.kind;
    x["in"] = l.in_channels;
    x["out"] = l.out_channels;
    x["kernel"] = l.kernel;
    x["output"] = std::to_string(l.out_width) + "x" + std::to_string(l.out_height);
    x["params"] = l.params;
    x["macs"] = l.macs;
    x["trainable"] = l.trainable;
    layers.push_back(x);
  }
  j["layers"] = layers;
  return j;
}

}  // namespace cgsr
