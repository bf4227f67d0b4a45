#include "models/backbones/span.h"

#include <torch/torch.h>

#include "models/reparameterization.h"

namespace cgsr {
namespace {

constexpr int64_t kDefaultFeatures = 48;
constexpr double kImageRange = 255.0;

std::vector<GroupDefault> span_groups(int, int blocks) {
  std::vector<GroupDefault> g = {{"features", kDefaultFeatures}};
  for (int i = 0; i < blocks; ++i) {
    g.push_back({block_group(i, "a"), kDefaultFeatures});
    g.push_back({block_group(i, "b"), kDefaultFeatures});
  }
  g.push_back({"trunk", kDefaultFeatures});
  g.push_back({"fuse", kDefaultFeatures});
  return g;
}

torch::nn::Conv2d conv(int64_t in, int64_t out, int64_t kernel, int64_t padding) {
  CGSR_CHECK(in > 0 && out > 0, "span: channel counts must be positive");
  ParameterBudget::charge_conv(in, out, kernel, 1, /*bias=*/true);
  return torch::nn::Conv2d(torch::nn::Conv2dOptions(in, out, kernel).padding(padding));
}

// The layout of `gain` channels per channel of `layout`, each group's channel's positions together.
graph::Layout repeated(graph::Layout layout, int64_t gain) {
  for (auto& segment : layout) segment.repeat *= gain;
  return layout;
}

torch::Tensor sigmoid_weighted(const torch::Tensor& x) { return x * torch::sigmoid(x); }  // SiLU
int describe_sigmoid_weighted(graph::Builder& g, int x) { return g.mul(x, g.sigmoid(x)); }

}  // namespace

// Called by register_builtin_backbones (backbone_registry.h: one file per backbone).
void register_backbone_span(Registry<BackboneInfo>& registry) {
  BackboneInfo info;
  info.description = "SPAN: swift parameter-free attention network (48 features, 6 SPABs, re-parameterized convs)";
  info.default_blocks = 6;
  info.min_blocks = 1;
  info.max_blocks = 64;
  info.has_hr_features = false;
  // conv_cat reads the first block's output and inside the last block: a network without them
  // (blocks renumbered) would read other values.
  info.fixed_blocks = [](int blocks) { return blocks > 1 ? std::vector<int>{0, blocks - 1} : std::vector<int>{0}; };
  info.block_group_suffixes = {"a", "b"};
  info.groups = span_groups;
  info.build = [](const ArchSpec& spec) -> std::shared_ptr<BackboneImpl> { return std::make_shared<SpanImpl>(spec); };
  registry.add("span", info, info.description);
}

// ---- re-parameterizable conv -------------------------------------------------------------------

RepConvImpl::RepConvImpl(int64_t in, int64_t out, int64_t gain) : gain_(gain) {
  expand = register_module("expand", conv(in, in * gain, 1, /*padding=*/1));
  spatial = register_module("spatial", conv(in * gain, out * gain, 3, /*padding=*/0));
  squeeze = register_module("squeeze", conv(out * gain, out, 1, 0));
  skip = register_module("skip", conv(in, out, 1, 0));
}

torch::Tensor RepConvImpl::forward(const torch::Tensor& x) {
  if (is_training()) return squeeze(spatial(expand(x))) + skip(x);
  const auto tensors = [](const torch::nn::Conv2d& c) { return ConvTensors{c->weight, c->bias}; };
  const auto folded = fold_branches(tensors(expand), tensors(spatial), tensors(squeeze), tensors(skip));
  return torch::conv2d(x, folded.weight, folded.bias, 1, spatial->weight.size(-1) / 2);
}

int RepConvImpl::describe(graph::Builder& g, int x, const graph::Layout& out) const {
  const int e = g.conv("expand", x, expand->weight, expand->bias, 1, repeated(g.value(x).layout, gain_));
  const int s = g.conv("spatial", e, spatial->weight, spatial->bias, 0, repeated(out, gain_));
  const int q = g.conv("squeeze", s, squeeze->weight, squeeze->bias, 0, out);
  return g.add(q, g.conv("skip", x, skip->weight, skip->bias, 0, out));
}

// ---- SPAB --------------------------------------------------------------------------------------

SpabImpl::SpabImpl(int index, int64_t features, int64_t a, int64_t b) : index_(index) {
  c1_r = register_module("c1_r", RepConv(features, a));
  c2_r = register_module("c2_r", RepConv(a, b));
  c3_r = register_module("c3_r", RepConv(b, features));
}

SpabImpl::Output SpabImpl::forward(const torch::Tensor& x) {
  const auto first = c1_r(x);
  const auto out3 = c3_r(sigmoid_weighted(c2_r(sigmoid_weighted(first))));
  const auto attention = graph::apply_affine(torch::sigmoid(out3), {}, torch::full({out3.size(1)}, -0.5, out3.options()));
  return {(out3 + x) * attention, first};
}

SpabImpl::Ports SpabImpl::describe(graph::Builder& g, int x) const {
  const auto group = [&](const char* suffix, const RepConv& c) {
    return graph::group_layout(block_group(index_, suffix), c->squeeze->weight.size(0));
  };
  auto scope = g.scope("blocks." + std::to_string(index_));
  const auto rep = [&](const char* name, const RepConv& c, int in, const graph::Layout& out) {
    auto inner = g.scope(name);
    return c->describe(g, in, out);
  };
  const int first = rep("c1_r", c1_r, x, group("a", c1_r));
  const int second = rep("c2_r", c2_r, describe_sigmoid_weighted(g, first), group("b", c2_r));
  const int out3 = rep("c3_r", c3_r, describe_sigmoid_weighted(g, second), g.value(x).layout);
  const int64_t c = c3_r->squeeze->weight.size(0);
  const int attention = g.affine("attention_shift", g.sigmoid(out3), {}, torch::full({c}, -0.5), /*trainable=*/false);
  return {g.mul(g.add(out3, x), attention), first};
}

// ---- SPAN --------------------------------------------------------------------------------------

SpanImpl::SpanImpl(const ArchSpec& spec) : scale_(spec.scale) {
  const auto mean = torch::tensor({0.4488f, 0.4371f, 0.4040f});  // the reference's RGB mean
  input_scale_ = torch::full({3}, kImageRange);
  input_shift_ = mean * -kImageRange;
  const int64_t nf = spec.group_width("features");
  conv_1 = register_module("conv_1", RepConv(3, nf));
  blocks = register_module("blocks", torch::nn::ModuleList());
  for (int i = 0; i < spec.blocks; ++i)
    blocks->push_back(Spab(i, nf, spec.group_width(block_group(i, "a")), spec.group_width(block_group(i, "b"))));
  const int64_t trunk = spec.group_width("trunk"), fuse = spec.group_width("fuse");
  const int64_t last_a = spec.group_width(block_group(spec.blocks - 1, "a"));
  conv_2 = register_module("conv_2", RepConv(nf, trunk));
  conv_cat = register_module("conv_cat", make_conv(nf + trunk + nf + last_a, fuse, 1));
  upsampler = register_module("upsampler", make_conv(fuse, 3 * scale_ * scale_, 3));
}

ExtractedFeatures SpanImpl::extract(const torch::Tensor& lr_color) {
  const auto head = conv_1(graph::apply_affine(lr_color, input_scale_, input_shift_));
  torch::Tensor x = head, first_block_out, last_first;
  for (size_t i = 0; i < blocks->size(); ++i) {
    auto out = (*blocks)[i]->as<Spab>()->forward(x);
    if (i == 0) first_block_out = out.out;
    last_first = out.first;
    x = out.out;
  }
  return {conv_cat(torch::cat({head, conv_2(x), first_block_out, last_first}, 1)), {}};
}

Reconstruction SpanImpl::reconstruct(const torch::Tensor& features, const torch::Tensor&, const HrFusion&) {
  return {torch::pixel_shuffle(upsampler(features), scale_), {}};
}

ExtractedPorts SpanImpl::describe_extract(graph::Builder& g, int color) const {
  const int64_t nf = conv_1->squeeze->weight.size(0);
  const int x0 = g.affine("sub_mean", color, input_scale_, input_shift_, /*trainable=*/false);
  int head = -1;
  {
    auto scope = g.scope("conv_1");
    head = conv_1->describe(g, x0, graph::group_layout("features", nf));
  }
  int x = head, first_block_out = -1, last_first = -1;
  for (size_t i = 0; i < blocks->size(); ++i) {
    const auto ports = (*blocks)[i]->as<Spab>()->describe(g, x);
    if (i == 0) first_block_out = ports.out;
    last_first = ports.first;
    x = ports.out;
  }
  int trunk = -1;
  {
    auto scope = g.scope("conv_2");
    trunk = conv_2->describe(g, x, graph::group_layout("trunk", conv_2->squeeze->weight.size(0)));
  }
  const int cat = g.concat({head, trunk, first_block_out, last_first});
  return {describe_conv(g, "conv_cat", conv_cat, cat, graph::group_layout("fuse", conv_cat->weight.size(0))), -1};
}

ReconstructionPorts SpanImpl::describe_reconstruct(graph::Builder& g, int features, int, const HrFusionPort&) const {
  const graph::Layout sub_pixels = {graph::Segment{"rgb", 3, scale_ * scale_, /*prunable=*/false}};
  const int up = describe_conv(g, "upsampler", upsampler, features, sub_pixels);
  return {g.pixel_shuffle(up, scale_), -1};
}

}  // namespace cgsr
