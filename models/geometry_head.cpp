#include "models/geometry_head.h"

#include <torch/torch.h>

#include "models/layers.h"
#include "models/rit.h"

namespace cgsr {
namespace {
}

GeometryHeadImpl::GeometryHeadImpl(int64_t in_channels, int64_t width, const std::vector<RenderChannel>& channels)
    : channels_(channels) {
  conv1 = register_module("conv1", make_conv(in_channels, width, 3));
  conv2 = register_module("conv2", make_conv(width, total_width(channels), 3));
}

torch::Tensor GeometryHeadImpl::forward(const torch::Tensor& hr_features) {
  return conv2(torch::leaky_relu(conv1(hr_features), kLeakySlope));
}

int GeometryHeadImpl::describe(graph::Builder& g, int hr_features) const {
  const int h = g.leaky_relu(
      describe_conv(g, "conv1", conv1, hr_features, graph::group_layout("geometry", conv1->weight.size(0))), kLeakySlope);
  return describe_conv(g, "conv2", conv2, h, info_layout(channels_));
}

}  // namespace cgsr
