#include "models/backbones/srcnn.h"

#include <torch/torch.h>

#include "core/color.h"

namespace cgsr {

// Called by register_builtin_backbones (backbone_registry.h: one file per backbone).
void register_backbone_srcnn(Registry<BackboneInfo>& registry) {
  BackboneInfo info;
  info.description = "SRCNN 9-5-5 (64/32 filters) on the bicubic-upsampled input, RGB or Y";
  info.default_blocks = 0;
  info.min_blocks = 0;
  info.max_blocks = 0;
  info.supports_y = true;
  info.groups = [](int, int) { return std::vector<GroupDefault>{{"conv1", 64}, {"conv2", 32}}; };
  info.build = [](const ArchSpec& spec) -> std::shared_ptr<BackboneImpl> { return std::make_shared<SrcnnImpl>(spec); };
  registry.add("srcnn", info, info.description);
}

SrcnnImpl::SrcnnImpl(const ArchSpec& spec) : scale_(spec.scale), luma_(spec.colors == Colors::Y) {
  const int64_t c = spec.color_channels();
  conv1 = register_module("conv1", make_conv(c, spec.group_width("conv1"), 9));
  conv2 = register_module("conv2", make_conv(spec.group_width("conv1"), spec.group_width("conv2"), 5));
  conv3 = register_module("conv3", make_conv(spec.group_width("conv2"), c, 5));
  if (luma_) {
    // The luma transform is read off core's rgb_to_y (y = bias + weights . rgb), in double.
    const auto basis = torch::cat({torch::zeros({1, 3, 1, 1}, torch::kDouble),
                                   torch::eye(3, torch::kDouble).view({3, 3, 1, 1})});
    const auto y = rgb_to_y(basis).flatten();  // [4]: y(0), y(e_r), y(e_g), y(e_b)
    const auto bias = y[0];
    const auto weights = y.slice(0, 1) - bias;   // [3]
    const auto gain = weights.sum();             // 219/255: luma of white minus black
    to_y_weight_ = weights.view({1, 3, 1, 1}).to(torch::kFloat);
    to_y_bias_ = bias.view({1}).to(torch::kFloat);
    // rgb' = rgb + (y' - y) / gain, with y = bias + weights . rgb
    const auto merge = torch::cat({torch::eye(3, torch::kDouble) - weights.view({1, 3}).expand({3, 3}) / gain,
                                   torch::full({3, 1}, 1.0, torch::kDouble) / gain},
                                  1);
    merge_weight_ = merge.view({3, 4, 1, 1}).to(torch::kFloat);
    merge_bias_ = (-bias / gain).expand({3}).contiguous().to(torch::kFloat);
  }
}

ExtractedFeatures SrcnnImpl::extract(const torch::Tensor& lr_color) {
  const auto up = graph::apply_resize(lr_color, scale_, graph::ResizeMode::Bicubic);
  auto x = luma_ ? torch::conv2d(up, to_y_weight_, to_y_bias_) : up;
  x = torch::relu(conv1(x));
  return {torch::relu(conv2(x)), up};
}

Reconstruction SrcnnImpl::reconstruct(const torch::Tensor& features_in, const torch::Tensor& skip,
                                      const HrFusion& at_hr) {
  // SRCNN's features are at HR already: the HR fusion point is the reconstruction's input.
  const auto features = at_hr ? at_hr(features_in) : features_in;
  auto out = conv3(features);
  if (luma_) out = torch::conv2d(torch::cat({skip, out}, 1), merge_weight_, merge_bias_);
  return {out, features};
}

ExtractedPorts SrcnnImpl::describe_extract(graph::Builder& g, int color) const {
  const int up = g.resize(color, scale_, graph::ResizeMode::Bicubic);
  int x = up;
  if (luma_) x = g.conv("to_y", up, to_y_weight_, to_y_bias_, 0, graph::fixed_layout("y", 1), /*trainable=*/false);
  x = g.relu(describe_conv(g, "conv1", conv1, x, graph::group_layout("conv1", conv1->weight.size(0))));
  x = g.relu(describe_conv(g, "conv2", conv2, x, graph::group_layout("conv2", conv2->weight.size(0))));
  return {x, up};
}

ReconstructionPorts SrcnnImpl::describe_reconstruct(graph::Builder& g, int features_in, int skip,
                                                    const HrFusionPort& at_hr) const {
  const int features = at_hr ? at_hr(features_in) : features_in;
  int out = describe_conv(g, "conv3", conv3, features, graph::fixed_layout(luma_ ? "y" : "rgb", luma_ ? 1 : 3));
  if (luma_)
    out = g.conv("merge_y", g.concat({skip, out}), merge_weight_, merge_bias_, 0, graph::fixed_layout("rgb", 3),
                 /*trainable=*/false);
  return {out, features};
}

}  // namespace cgsr
