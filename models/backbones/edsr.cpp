#include "models/backbones/edsr.h"

#include <torch/torch.h>

namespace cgsr {
namespace {
std::vector<GroupDefault> edsr_groups(int scale, int blocks) {
  std::vector<GroupDefault> g = {{"features", 64}};
  for (int i = 0; i < blocks; ++i) g.push_back({block_group(i, "mid"), 64});
  g.push_back({"up1", 64});
  if (scale == 4) g.push_back({"up2", 64});
  return g;
}
}  // namespace

// Called by register_builtin_backbones (backbone_registry.h: one file per backbone).
void register_backbone_edsr(Registry<BackboneInfo>& registry) {
  BackboneInfo info;
  info.description = "EDSR-baseline: 64 features, 16 residual blocks, pixel-shuffle upsampler";
  info.default_blocks = 16;
  info.min_blocks = 1;
  info.max_blocks = 64;
  info.block_group_suffixes = {"mid"};
  info.groups = edsr_groups;
  info.build = [](const ArchSpec& spec) -> std::shared_ptr<BackboneImpl> { return std::make_shared<EdsrImpl>(spec); };
  registry.add("edsr", info, info.description);
}

EdsrBlockImpl::EdsrBlockImpl(int index, int64_t features, int64_t mid) : index_(index) {
  conv1 = register_module("conv1", make_conv(features, mid, 3));
  conv2 = register_module("conv2", make_conv(mid, features, 3));
}

// res_scale is 1 in EDSR-baseline, so the residual is added unscaled.
torch::Tensor EdsrBlockImpl::forward(const torch::Tensor& x) { return conv2(torch::relu(conv1(x))) + x; }

int EdsrBlockImpl::describe(graph::Builder& g, int x) const {
  auto scope = g.scope("blocks." + std::to_string(index_));
  const int y = g.relu(describe_conv(g, "conv1", conv1, x,
                                     graph::group_layout(block_group(index_, "mid"), conv1->weight.size(0))));
  return g.add(describe_conv(g, "conv2", conv2, y, g.value(x).layout), x);
}

EdsrImpl::EdsrImpl(const ArchSpec& spec) {
  stage_factors_ = spec.scale == 4 ? std::vector<int64_t>{2, 2} : std::vector<int64_t>{spec.scale};
  shift_weight_ = torch::eye(3).view({3, 3, 1, 1});
  mean_ = torch::tensor({0.4488f, 0.4371f, 0.4040f});
  neg_mean_ = -mean_;
  const int64_t nf = spec.group_width("features");
  head = register_module("head", make_conv(3, nf, 3));
  blocks = register_module("blocks", torch::nn::ModuleList());
  for (int i = 0; i < spec.blocks; ++i) blocks->push_back(EdsrBlock(i, nf, spec.group_width(block_group(i, "mid"))));
  body_conv = register_module("body_conv", make_conv(nf, nf, 3));
  int64_t in = nf;
  for (size_t s = 0; s < stage_factors_.size(); ++s) {
    const int64_t r = stage_factors_[s];
    const int64_t out = spec.group_width("up" + std::to_string(s + 1));
    upsample_.push_back(register_module("upsample" + std::to_string(s + 1), make_conv(in, out * r * r, 3)));
    in = out;
  }
  tail = register_module("tail", make_conv(in, 3, 3));
}

ExtractedFeatures EdsrImpl::extract(const torch::Tensor& lr_color) {
  const auto h = head(torch::conv2d(lr_color, shift_weight_, neg_mean_));
  auto res = h;
  for (const auto& block : *blocks) res = block->as<EdsrBlock>()->forward(res);
  return {body_conv(res) + h, {}};
}

Reconstruction EdsrImpl::reconstruct(const torch::Tensor& features, const torch::Tensor&, const HrFusion& at_hr) {
  auto x = features;
  for (size_t s = 0; s < upsample_.size(); ++s) x = torch::pixel_shuffle(upsample_[s](x), stage_factors_[s]);
  if (at_hr) x = at_hr(x);
  return {torch::conv2d(tail(x), shift_weight_, mean_), x};
}

ExtractedPorts EdsrImpl::describe_extract(graph::Builder& g, int color) const {
  const int64_t nf = head->weight.size(0);
  const int x = g.conv("sub_mean", color, shift_weight_, neg_mean_, 0, graph::fixed_layout("rgb", 3), false);
  const int h = describe_conv(g, "head", head, x, graph::group_layout("features", nf));
  int res = h;
  for (const auto& block : *blocks) res = block->as<EdsrBlock>()->describe(g, res);
  return {g.add(describe_conv(g, "body_conv", body_conv, res, graph::group_layout("features", nf)), h), -1};
}

ReconstructionPorts EdsrImpl::describe_reconstruct(graph::Builder& g, int features, int,
                                                   const HrFusionPort& at_hr) const {
  int x = features;
  for (size_t s = 0; s < upsample_.size(); ++s) {
    const int64_t r = stage_factors_[s];
    const std::string group = "up" + std::to_string(s + 1);
    const auto& conv = upsample_[s];
    x = describe_conv(g, "upsample" + std::to_string(s + 1), conv, x,
                      graph::group_layout(group, conv->weight.size(0) / (r * r), r * r));
    x = g.pixel_shuffle(x, r);
  }
  if (at_hr) x = at_hr(x);
  const int out = describe_conv(g, "tail", tail, x, graph::fixed_layout("rgb", 3));
  return {g.conv("add_mean", out, shift_weight_, mean_, 0, graph::fixed_layout("rgb", 3), /*trainable=*/false), x};
}

}  // namespace cgsr
