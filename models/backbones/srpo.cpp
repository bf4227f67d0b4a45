#include "models/backbones/srpo.h"

#include <torch/torch.h>

#include <cmath>

namespace cgsr {
namespace {

constexpr int64_t kWidth = 16;
constexpr int64_t kKernel = 5;
constexpr double kBlurSigma = 1.5;

// The paper's 3x3 Gaussian (sigma 1.5), normalized, as a [3, 1, 3, 3] conv from the 1-channel
// mask to one alpha per colour channel (so the blend's products need no broadcasting).
torch::Tensor blend_blur() {
  const double side = std::exp(-1.0 / (2.0 * kBlurSigma * kBlurSigma));
  auto g = torch::tensor({side, 1.0, side}, torch::kDouble);
  auto k = torch::outer(g, g);
  k = k / k.sum();
  return k.view({1, 1, 3, 3}).expand({3, 1, 3, 3}).contiguous().to(torch::kFloat);
}

}  // namespace

// Called by register_builtin_backbones (backbone_registry.h: one file per backbone).
void register_backbone_srpo(Registry<BackboneInfo>& registry) {
  BackboneInfo info;
  info.description = "SRPO: offsets from 3 convs (5x5, 16 features) move LR pixels; blended with bicubic (8,434 params)";
  info.default_blocks = 0;
  info.min_blocks = 0;
  info.max_blocks = 0;
  info.groups = [](int, int) { return std::vector<GroupDefault>{{"conv1", kWidth}, {"conv2", kWidth}}; };
  info.build = [](const ArchSpec& spec) -> std::shared_ptr<BackboneImpl> { return std::make_shared<SrpoImpl>(spec); };
  registry.add("srpo", info, info.description);
}

SrpoImpl::SrpoImpl(const ArchSpec& spec) : scale_(spec.scale) {
  conv1 = register_module("conv1", make_conv(3, spec.group_width("conv1"), kKernel));
  conv2 = register_module("conv2", make_conv(spec.group_width("conv1"), spec.group_width("conv2"), kKernel));
  conv3 = register_module("conv3", make_conv(spec.group_width("conv2"), 2, kKernel));
  blur_ = blend_blur();
  complement_scale_ = torch::full({3}, -1.0f);
  complement_shift_ = torch::full({3}, 1.0f);
}

ExtractedFeatures SrpoImpl::extract(const torch::Tensor& lr_color) {
  return {torch::relu(conv2(torch::relu(conv1(lr_color)))), lr_color};
}

Reconstruction SrpoImpl::reconstruct(const torch::Tensor& features, const torch::Tensor& skip, const HrFusion& at_hr) {
  auto hr = graph::apply_resize(features, scale_, graph::ResizeMode::Nearest);
  if (at_hr) hr = at_hr(hr);
  const auto omega = conv3(hr);
  if (is_training()) return {graph::apply_sample(skip, omega, scale_, graph::ResizeMode::Bilinear), hr};
  const auto projected = graph::apply_sample(skip, omega, scale_, graph::ResizeMode::Nearest);
  const auto alpha = torch::conv2d(graph::apply_any_abs_above(omega, kSrpoMovedThreshold), blur_, {}, 1, 1);
  const auto interpolated = graph::apply_resize(skip, scale_, graph::ResizeMode::Bicubic);
  const auto keep = graph::apply_affine(alpha, complement_scale_, complement_shift_);
  return {alpha * projected + keep * interpolated, hr};
}

ExtractedPorts SrpoImpl::describe_extract(graph::Builder& g, int color) const {
  int x = g.relu(describe_conv(g, "conv1", conv1, color, graph::group_layout("conv1", conv1->weight.size(0))));
  x = g.relu(describe_conv(g, "conv2", conv2, x, graph::group_layout("conv2", conv2->weight.size(0))));
  return {x, color};
}

ReconstructionPorts SrpoImpl::describe_reconstruct(graph::Builder& g, int features, int skip,
                                                   const HrFusionPort& at_hr) const {
  int hr = g.resize(features, scale_, graph::ResizeMode::Nearest);
  if (at_hr) hr = at_hr(hr);
  const int omega = describe_conv(g, "conv3", conv3, hr, graph::fixed_layout("offsets", 2));
  if (g.training()) return {g.sample(skip, omega, graph::ResizeMode::Bilinear), hr};
  const int projected = g.sample(skip, omega, graph::ResizeMode::Nearest);
  const int moved = g.any_abs_above(omega, kSrpoMovedThreshold);
  const int alpha = g.conv("blend_blur", moved, blur_, {}, 1, graph::fixed_layout("rgb", 3), /*trainable=*/false);
  const int interpolated = g.resize(skip, scale_, graph::ResizeMode::Bicubic);
  const int keep = g.affine("blend_complement", alpha, complement_scale_, complement_shift_, /*trainable=*/false);
  return {g.add(g.mul(alpha, projected), g.mul(keep, interpolated)), hr};
}

}  // namespace cgsr
