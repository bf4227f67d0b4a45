#include "models/rit.h"

#include <torch/torch.h>

#include "core/error.h"
#include "models/layers.h"

namespace cgsr {
namespace {
}

graph::Layout info_layout(const std::vector<RenderChannel>& channels) {
  graph::Layout layout;
  for (auto c : channels) layout.push_back(graph::Segment{"info:" + channel_name(c), channel_width(c), 1, false});
  return layout;
}

RitBlockImpl::RitBlockImpl(const RitSpec& rit, int scale, std::string feature_group, int64_t feature_channels,
                           int64_t feature_factor)
    : concat_(rit.fusion == "concat"),
      pool_factor_(rit.source == "hr_pooled" ? scale : 1),
      upsample_factor_(feature_factor),
      feature_group_(std::move(feature_group)),
      channels_(rit.render_channels()) {
  const int64_t c = total_width(channels_);
  CGSR_CHECK(c > 0 && rit.width > 0, "RIT needs channels and a positive width");
  gate = register_parameter("gate", torch::ones({c}));
  conv = register_module("conv", make_conv(c, rit.width, 3));
  fuse = register_module("fuse", make_conv(concat_ ? feature_channels + rit.width : rit.width, feature_channels, 1));
  zero_conv(fuse);
}

torch::Tensor RitBlockImpl::forward(const torch::Tensor& features, const torch::Tensor& info) {
  auto x = pool_factor_ > 1 ? graph::apply_avg_pool(info, pool_factor_) : info;
  x = graph::apply_affine(x, gate, {});
  x = torch::leaky_relu(conv(x), kLeakySlope);
  if (upsample_factor_ > 1) x = graph::apply_resize(x, upsample_factor_, graph::ResizeMode::Bilinear);
  return features + fuse(concat_ ? torch::cat({features, x}, 1) : x);
}

int RitBlockImpl::describe(graph::Builder& g, int features, int info) const {
  int x = pool_factor_ > 1 ? g.avg_pool(info, pool_factor_) : info;
  x = g.affine("gate", x, gate, {}, /*trainable=*/true);
  x = g.leaky_relu(describe_conv(g, "conv", conv, x, graph::group_layout("rit", conv->weight.size(0))), kLeakySlope);
  if (upsample_factor_ > 1) x = g.resize(x, upsample_factor_, graph::ResizeMode::Bilinear);
  const int fused = describe_conv(g, "fuse", fuse, concat_ ? g.concat({features, x}) : x, g.value(features).layout);
  return g.add(features, fused);
}

}  // namespace cgsr
