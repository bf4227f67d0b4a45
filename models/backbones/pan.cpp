#include "models/backbones/pan.h"

#include <torch/torch.h>

namespace cgsr {
namespace {

// In place: every activation here applies to a fresh conv or product output that autograd has
// not saved, so this spares a 12 MB allocation and pass per call at 320x240 (the values, and
// so graph::run's bit-equality with forward(), are unchanged).
torch::Tensor lrelu(torch::Tensor x) { return torch::leaky_relu_(x, kLeakySlope); }

const std::vector<std::string>& block_suffixes() {
  static const std::vector<std::string> s = {"a", "a_out", "b", "att", "b_out"};
  return s;
}

std::vector<GroupDefault> pan_groups(int scale, int blocks) {
  std::vector<GroupDefault> g = {{"features", 40}};
  for (int i = 0; i < blocks; ++i)
    for (const auto& suffix : block_suffixes()) g.push_back({block_group(i, suffix), 20});
  g.push_back({"up1", 24});
  g.push_back({"hr1", 24});
  if (scale == 4) {
    g.push_back({"up2", 24});
    g.push_back({"hr2", 24});
  }
  return g;
}
}  // namespace

// Called by register_builtin_backbones (backbone_registry.h: one file per backbone).
void register_backbone_pan(Registry<BackboneInfo>& registry) {
  BackboneInfo info;
  info.description = "PAN: pixel attention network (nf 40, unf 24, 16 SC-PA blocks)";
  info.default_blocks = 16;
  info.min_blocks = 1;
  info.max_blocks = 64;
  info.has_image_skip = true;
  info.block_group_suffixes = block_suffixes();
  info.groups = pan_groups;
  info.build = [](const ArchSpec& spec) -> std::shared_ptr<BackboneImpl> { return std::make_shared<PanImpl>(spec); };
  registry.add("pan", info, info.description);
}

// ---- pixel attention ---------------------------------------------------------------------------

PixelAttentionImpl::PixelAttentionImpl(int64_t channels) {
  conv = register_module("conv", make_conv(channels, channels, 1));
}

torch::Tensor PixelAttentionImpl::forward(const torch::Tensor& x) { return x * conv(x).sigmoid_(); }

int PixelAttentionImpl::describe(graph::Builder& g, int x, const std::string& group) const {
  const int64_t c = graph::layout_width(g.value(x).layout);
  const int y = g.sigmoid(describe_conv(g, "conv", conv, x, graph::group_layout(group, c)));
  return g.mul(x, y);
}

PAConvImpl::PAConvImpl(int64_t in, int64_t att, int64_t out) {
  k2 = register_module("k2", make_conv(in, att, 1));
  k3 = register_module("k3", make_conv(in, att, 3, /*bias=*/false));
  k4 = register_module("k4", make_conv(att, out, 3, /*bias=*/false));
}

torch::Tensor PAConvImpl::forward(const torch::Tensor& x) {
  const auto y = k2(x).sigmoid_();
  return k4(k3(x).mul_(y));
}

int PAConvImpl::describe(graph::Builder& g, int x, const std::string& att_group, const std::string& out_group) const {
  const int y = g.sigmoid(describe_conv(g, "k2", k2, x, graph::group_layout(att_group, k2->weight.size(0))));
  const int z = describe_conv(g, "k3", k3, x, graph::group_layout(att_group, k3->weight.size(0)));
  return describe_conv(g, "k4", k4, g.mul(z, y), graph::group_layout(out_group, k4->weight.size(0)));
}

// ---- SC-PA block -------------------------------------------------------------------------------

ScpaBlockImpl::ScpaBlockImpl(int index, const ScpaWidths& w) : index_(index) {
  conv1_a = register_module("conv1_a", make_conv(w.features, w.a, 1, /*bias=*/false));
  conv1_b = register_module("conv1_b", make_conv(w.features, w.b, 1, /*bias=*/false));
  k1 = register_module("k1", make_conv(w.a, w.a_out, 3, /*bias=*/false));
  pa_conv = register_module("pa_conv", PAConv(w.b, w.att, w.b_out));
  conv3 = register_module("conv3", make_conv(w.a_out + w.b_out, w.features, 1, /*bias=*/false));
}

torch::Tensor ScpaBlockImpl::forward(const torch::Tensor& x) {
  auto a = lrelu(conv1_a(x));
  auto b = lrelu(conv1_b(x));
  a = lrelu(k1(a));
  b = lrelu(pa_conv(b));
  return conv3(torch::cat({a, b}, 1)).add_(x);
}

int ScpaBlockImpl::describe(graph::Builder& g, int x) const {
  const auto group = [&](const char* suffix) { return block_group(index_, suffix); };
  const auto width = [](const torch::nn::Conv2d& c) { return c->weight.size(0); };
  auto scope = g.scope("blocks." + std::to_string(index_));
  int a = g.leaky_relu(describe_conv(g, "conv1_a", conv1_a, x, graph::group_layout(group("a"), width(conv1_a))), kLeakySlope);
  int b = g.leaky_relu(describe_conv(g, "conv1_b", conv1_b, x, graph::group_layout(group("b"), width(conv1_b))), kLeakySlope);
  a = g.leaky_relu(describe_conv(g, "k1", k1, a, graph::group_layout(group("a_out"), width(k1))), kLeakySlope);
  {
    auto pa_scope = g.scope("pa_conv");
    b = pa_conv->describe(g, b, group("att"), group("b_out"));
  }
  b = g.leaky_relu(b, kLeakySlope);
  const int out = describe_conv(g, "conv3", conv3, g.concat({a, b}), g.value(x).layout);
  return g.add(out, x);
}

// ---- PAN ---------------------------------------------------------------------------------------

PanImpl::PanImpl(const ArchSpec& spec)
    : scale_(spec.scale),
      skip_mode_(spec.image_skip == ImageSkip::Bicubic ? graph::ResizeMode::Bicubic : graph::ResizeMode::Bilinear) {
  stages_ = spec.scale == 4 ? 2 : 1;
  stage_factor_ = spec.scale == 4 ? 2 : spec.scale;
  const int64_t nf = spec.group_width("features");
  conv_first = register_module("conv_first", make_conv(3, nf, 3));
  blocks = register_module("blocks", torch::nn::ModuleList());
  for (int i = 0; i < spec.blocks; ++i) {
    ScpaWidths w;
    w.features = nf;
    w.a = spec.group_width(block_group(i, "a"));
    w.a_out = spec.group_width(block_group(i, "a_out"));
    w.b = spec.group_width(block_group(i, "b"));
    w.att = spec.group_width(block_group(i, "att"));
    w.b_out = spec.group_width(block_group(i, "b_out"));
    blocks->push_back(ScpaBlock(i, w));
  }
  trunk_conv = register_module("trunk_conv", make_conv(nf, nf, 3));
  const int64_t up1 = spec.group_width("up1"), hr1 = spec.group_width("hr1");
  upconv1 = register_module("upconv1", make_conv(nf, up1, 3));
  att1 = register_module("att1", PixelAttention(up1));
  hr_conv1 = register_module("hr_conv1", make_conv(up1, hr1, 3));
  int64_t last = hr1;
  if (stages_ == 2) {
    const int64_t up2 = spec.group_width("up2"), hr2 = spec.group_width("hr2");
    upconv2 = register_module("upconv2", make_conv(hr1, up2, 3));
    att2 = register_module("att2", PixelAttention(up2));
    hr_conv2 = register_module("hr_conv2", make_conv(up2, hr2, 3));
    last = hr2;
  }
  conv_last = register_module("conv_last", make_conv(last, 3, 3));
}

ExtractedFeatures PanImpl::extract(const torch::Tensor& lr_color) {
  const auto fea = conv_first(lr_color);
  auto trunk = fea;
  for (const auto& block : *blocks) trunk = block->as<ScpaBlock>()->forward(trunk);
  return {trunk_conv(trunk).add_(fea), lr_color};
}

Reconstruction PanImpl::reconstruct(const torch::Tensor& features, const torch::Tensor& skip, const HrFusion& at_hr) {
  auto fea = upconv1(graph::apply_resize(features, stage_factor_, graph::ResizeMode::Nearest));
  fea = lrelu(att1(fea));
  if (stages_ == 1 && at_hr) fea = at_hr(fea);
  fea = lrelu(hr_conv1(fea));
  if (stages_ == 2) {
    fea = upconv2(graph::apply_resize(fea, stage_factor_, graph::ResizeMode::Nearest));
    fea = lrelu(att2(fea));
    if (at_hr) fea = at_hr(fea);
    fea = lrelu(hr_conv2(fea));
  }
  const auto out = conv_last(fea).add_(graph::apply_resize(skip, scale_, skip_mode_));
  return {out, fea};
}

ExtractedPorts PanImpl::describe_extract(graph::Builder& g, int color) const {
  const auto nf = conv_first->weight.size(0);
  const int fea = describe_conv(g, "conv_first", conv_first, color, graph::group_layout("features", nf));
  int trunk = fea;
  for (const auto& block : *blocks) trunk = block->as<ScpaBlock>()->describe(g, trunk);
  trunk = describe_conv(g, "trunk_conv", trunk_conv, trunk, graph::group_layout("features", nf));
  return {g.add(trunk, fea), color};
}

ReconstructionPorts PanImpl::describe_reconstruct(graph::Builder& g, int features, int skip,
                                                  const HrFusionPort& at_hr) const {
  const auto stage = [&](int x, const char* up_name, const torch::nn::Conv2d& up, const char* att_name,
                         const PixelAttention& att, const char* hr_name, const torch::nn::Conv2d& hr,
                         const std::string& up_group, const std::string& hr_group, bool last) {
    int y = g.resize(x, stage_factor_, graph::ResizeMode::Nearest);
    y = describe_conv(g, up_name, up, y, graph::group_layout(up_group, up->weight.size(0)));
    {
      auto scope = g.scope(att_name);
      y = att->describe(g, y, up_group);
    }
    y = g.leaky_relu(y, kLeakySlope);
    if (last && at_hr) y = at_hr(y);
    return g.leaky_relu(describe_conv(g, hr_name, hr, y, graph::group_layout(hr_group, hr->weight.size(0))), kLeakySlope);
  };
  int fea = stage(features, "upconv1", upconv1, "att1", att1, "hr_conv1", hr_conv1, "up1", "hr1", stages_ == 1);
  if (stages_ == 2) fea = stage(fea, "upconv2", upconv2, "att2", att2, "hr_conv2", hr_conv2, "up2", "hr2", true);
  const int out = describe_conv(g, "conv_last", conv_last, fea, graph::fixed_layout("rgb", 3));
  const int ilr = g.resize(skip, scale_, skip_mode_);
  return {g.add(out, ilr), fea};
}

}  // namespace cgsr
