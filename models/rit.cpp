#include "models/rit.h"

#include <torch/torch.h>

#include <algorithm>

#include "core/error.h"
#include "models/layers.h"

namespace cgsr {

graph::Layout info_layout(const std::vector<RenderChannel>& channels) {
  graph::Layout layout;
  for (auto c : channels) layout.push_back(graph::Segment{"info:" + channel_name(c), channel_width(c), 1, false});
  return layout;
}

namespace {

// features + 1x1(cat(features, x)) or features + 1x1(x), starting at zero.
torch::nn::Conv2d make_fusion(bool concat, int64_t feature_channels, int64_t width) {
  auto fuse = make_conv(concat ? feature_channels + width : width, feature_channels, 1);
  zero_conv(fuse);
  return fuse;
}

// The first position of `channel` in an info tensor of `channels`.
int64_t channel_offset(const std::vector<RenderChannel>& channels, RenderChannel channel) {
  int64_t offset = 0;
  for (auto c : channels) {
    if (c == channel) return offset;
    offset += channel_width(c);
  }
  throw Error("RIT", "needs the " + channel_name(channel) + " channel");
}

// [3, C, 1, 1]: output k picks input channel `first` + k (stride 1), or `first` for all three (stride 0).
torch::Tensor selection(int64_t c, int64_t first, int64_t stride) {
  auto s = torch::zeros({3, c, 1, 1});
  for (int64_t k = 0; k < 3; ++k) s[k][first + stride * k] = 1.0f;
  return s;
}

}  // namespace

RitBlockImpl::RitBlockImpl(const RitSpec& rit, int scale, FusionPoint features, FusionPoint hr_features)
    : concat_(rit.fusion == RitFusion::Concat),
      info_factor_(rit.reads_hr() ? scale : 1),
      pool_factor_(rit.source == RitSource::HrPooled ? scale : 1),
      stride_(rit.unshuffles() ? scale : 1),
      upsample_factor_(features.factor),
      scale_(scale) {
  const int64_t c = total_width(rit.render_channels());
  CGSR_CHECK(c > 0 && rit.width > 0 && rit.hr_width > 0, "RIT needs channels and positive widths");
  ParameterBudget::charge(c);
  gate = register_parameter("gate", torch::ones({c}));
  const auto convolved = rit.convolved_channels();
  const int64_t read = total_width(convolved);
  if (!rit.feature_channels.empty()) {
    feature_layout_ = info_layout(convolved);
    feature_select_ = torch::zeros({read, c, 1, 1});
    int64_t row = 0;
    for (auto channel : convolved)
      for (int64_t k = 0; k < channel_width(channel); ++k, ++row)
        feature_select_[row][channel_offset(rit.render_channels(), channel) + k] = 1.0f;
  }
  if (rit.feature_branch()) {
    // Space-to-depth + conv 3x3 == a conv of kernel 3s, stride s, padding s on the HR map.
    ParameterBudget::charge_conv(read, rit.width, 3 * stride_, 1, /*bias=*/true);
    conv = register_module("conv", torch::nn::Conv2d(torch::nn::Conv2dOptions(read, rit.width, 3 * stride_)
                                                         .stride(stride_)
                                                         .padding(stride_)));
    fuse = register_module("fuse", make_fusion(concat_, features.channels, rit.width));
  }
  if (rit.hr_branch()) {
    CGSR_CHECK(hr_features.factor == scale, "RIT: the HR fusion point must be at the output resolution");
    hr_conv = register_module("hr_conv", make_conv(read, rit.hr_width, 3));
    hr_fuse = register_module("hr_fuse", make_fusion(concat_, hr_features.channels, rit.hr_width));
  }
  if (rit.bsp_composite) {
    CGSR_CHECK(info_factor_ == scale, "RIT: bsp_composite needs the information at the output resolution");
    const int64_t offset = channel_offset(rit.render_channels(), RenderChannel::Bsp);
    bsp_color_ = selection(c, offset, 1);
    bsp_coverage_ = selection(c, offset + 3, 0);
    complement_scale_ = torch::full({3}, -1.0f);
    complement_shift_ = torch::full({3}, 1.0f);
  }
  const auto& channels = rit.render_channels();
  const bool recurrent = std::find(channels.begin(), channels.end(), RenderChannel::HistoryOut) != channels.end();
  if (recurrent) {
    CGSR_CHECK(info_factor_ == scale, "RIT: history_out needs the information at the output resolution");
    const int64_t offset = channel_offset(channels, RenderChannel::HistoryOut);
    previous_color_ = selection(c, offset, 1);
    previous_validity_ = selection(c, offset + 3, 0);
    previous_motion_ = torch::zeros({2, c, 1, 1});
    previous_motion_[0][offset + 4] = 1.0f;
    previous_motion_[1][offset + 5] = 1.0f;
    previous_keep_ = torch::eye(c).view({c, c, 1, 1});
    for (int64_t k : {0, 1, 2, 4, 5}) previous_keep_[offset + k][offset + k] = 0.0f;
    previous_embed_ = torch::zeros({c, 3, 1, 1});
    for (int64_t k = 0; k < 3; ++k) previous_embed_[offset + k][k] = 1.0f;
    previous_warp_ = rit.history_warp == WarpFilter::Bicubic ? graph::ResizeMode::Bicubic : graph::ResizeMode::Bilinear;
  }
  if (rit.history_blend) {
    CGSR_CHECK(info_factor_ == scale, "RIT: history_blend needs the information at the output resolution");
    // The recurrent history when there is one: every frame so far, where the sampled one has five.
    const int64_t offset = channel_offset(channels, recurrent ? RenderChannel::HistoryOut : RenderChannel::History);
    history_color_ = selection(c, offset, 1);
    history_recency_ = selection(c, offset + 3, 0);
    ParameterBudget::charge_conv(3 + c, 3, 3, 1, /*bias=*/true);
    blend = register_module("blend", make_conv(3 + c, 3, 3));
    zero_conv(blend);
    torch::NoGradGuard no_grad;
    blend->bias.fill_(-4.0f);
  }
  if (rit.skip_at_jitter) {
    CGSR_CHECK(info_factor_ == scale, "RIT: skip_at_jitter needs the information at the output resolution");
    const int64_t offset = channel_offset(rit.render_channels(), RenderChannel::Jitter);
    jitter_offsets_ = torch::zeros({2, c, 1, 1});
    jitter_offsets_[0][offset] = 1.0f;
    jitter_offsets_[1][offset + 1] = 1.0f;
    if (rit.residual_at_jitter) hr_jitter_offsets_ = jitter_offsets_ * static_cast<float>(scale);
  }
  if (rit.history_blend || rit.skip_at_jitter) {
    negate_scale_ = torch::full({3}, -1.0f);
    negate_shift_ = torch::zeros({3});
  }
}

torch::Tensor RitBlockImpl::warp_previous_output(const torch::Tensor& info) const {
  if (!reads_previous_output()) return info;
  // The kernels and the operand order of describe_warp_previous_output(), so both give the same bits.
  const auto warped =
      graph::apply_sample(torch::conv2d(info, previous_color_), torch::conv2d(info, previous_motion_), 1, previous_warp_);
  return torch::conv2d(info, previous_keep_) + torch::conv2d(warped * torch::conv2d(info, previous_validity_), previous_embed_);
}

int RitBlockImpl::describe_warp_previous_output(graph::Builder& g, int info) const {
  if (!reads_previous_output()) return info;
  const auto rgb = graph::fixed_layout("rgb", 3);
  const auto layout = g.value(info).layout;
  const int color = g.conv("previous_color", info, previous_color_, {}, 0, rgb, /*trainable=*/false);
  const int motion = g.conv("previous_motion", info, previous_motion_, {}, 0, graph::fixed_layout("motion", 2),
                            /*trainable=*/false);
  const int warped = g.sample(color, motion, previous_warp_);
  const int validity = g.conv("previous_validity", info, previous_validity_, {}, 0, rgb, /*trainable=*/false);
  const int kept = g.conv("previous_keep", info, previous_keep_, {}, 0, layout, /*trainable=*/false);
  return g.add(kept, g.conv("previous_embed", g.mul(warped, validity), previous_embed_, {}, 0, layout,
                            /*trainable=*/false));
}

torch::Tensor RitBlockImpl::gate_info(const torch::Tensor& info) const {
  const auto x = pool_factor_ > 1 ? graph::apply_avg_pool(info, pool_factor_) : info;
  const auto gated = graph::apply_affine(x, gate, {});
  return feature_select_.defined() ? torch::conv2d(gated, feature_select_) : gated;
}

torch::Tensor RitBlockImpl::join(const torch::Tensor& features, const torch::Tensor& x, torch::nn::Conv2d& fusion) {
  return features + fusion(concat_ ? torch::cat({features, x}, 1) : x);
}

int RitBlockImpl::describe_join(graph::Builder& g, const std::string& name, const torch::nn::Conv2d& fusion,
                                int features, int x) const {
  const int fused = describe_conv(g, name, fusion, concat_ ? g.concat({features, x}) : x, g.value(features).layout);
  return g.add(features, fused);
}

torch::Tensor RitBlockImpl::fuse_features(const torch::Tensor& features, const torch::Tensor& gated) {
  auto x = torch::leaky_relu(conv(gated), kLeakySlope);
  if (upsample_factor_ > 1) x = graph::apply_resize(x, upsample_factor_, graph::ResizeMode::Bilinear);
  return join(features, x, fuse);
}

torch::Tensor RitBlockImpl::fuse_hr(const torch::Tensor& hr_features, const torch::Tensor& gated) {
  return join(hr_features, torch::leaky_relu(hr_conv(gated), kLeakySlope), hr_fuse);
}

int RitBlockImpl::describe_gate(graph::Builder& g, int info) const {
  const int x = pool_factor_ > 1 ? g.avg_pool(info, pool_factor_) : info;
  const int gated = g.affine("gate", x, gate, {}, /*trainable=*/true);
  if (!feature_select_.defined()) return gated;
  return g.conv("feature_select", gated, feature_select_, {}, 0, feature_layout_, /*trainable=*/false);
}

int RitBlockImpl::describe_features(graph::Builder& g, int features, int gated) const {
  // Kernel 3s, padding s (one LR pixel), stride s.
  int x = g.conv("conv", gated, conv->weight, conv->bias, /*padding=*/stride_,
                 graph::group_layout("rit", conv->weight.size(0)), /*trainable=*/true, stride_);
  x = g.leaky_relu(x, kLeakySlope);
  if (upsample_factor_ > 1) x = g.resize(x, upsample_factor_, graph::ResizeMode::Bilinear);
  return describe_join(g, "fuse", fuse, features, x);
}

int RitBlockImpl::describe_hr(graph::Builder& g, int hr_features, int gated) const {
  const int x = g.leaky_relu(
      describe_conv(g, "hr_conv", hr_conv, gated, graph::group_layout("rit_hr", hr_conv->weight.size(0))), kLeakySlope);
  return describe_join(g, "hr_fuse", hr_fuse, hr_features, x);
}

torch::Tensor RitBlockImpl::composite_bsp(const torch::Tensor& image, const torch::Tensor& info) const {
  // The kernels and the operand order of describe_composite_bsp(), so both give the same bits.
  const auto covered = torch::conv2d(info, bsp_coverage_);
  const auto kept = graph::apply_affine(covered, complement_scale_, complement_shift_);
  return kept * image + covered * torch::conv2d(info, bsp_color_);
}

int RitBlockImpl::describe_composite_bsp(graph::Builder& g, int image, int info) const {
  const auto rgb = g.value(image).layout;
  const int covered = g.conv("bsp_coverage", info, bsp_coverage_, {}, 0, rgb, /*trainable=*/false);
  const int kept = g.affine("bsp_complement", covered, complement_scale_, complement_shift_, /*trainable=*/false);
  const int bsp = g.conv("bsp_color", info, bsp_color_, {}, 0, rgb, /*trainable=*/false);
  return g.add(g.mul(kept, image), g.mul(covered, bsp));
}

torch::Tensor RitBlockImpl::blend_history(const torch::Tensor& image, const torch::Tensor& info) {
  // The kernels and the operand order of describe_blend_history(), so both give the same bits.
  const auto weight = torch::sigmoid(blend(torch::cat({image, info}, 1))) * torch::conv2d(info, history_recency_);
  const auto difference = torch::conv2d(info, history_color_) + graph::apply_affine(image, negate_scale_, negate_shift_);
  return image + weight * difference;
}

int RitBlockImpl::describe_blend_history(graph::Builder& g, int image, int info) const {
  const auto rgb = g.value(image).layout;
  const int logit = describe_conv(g, "blend", blend, g.concat({image, info}), rgb);
  const int recency = g.conv("history_recency", info, history_recency_, {}, 0, rgb, /*trainable=*/false);
  const int weight = g.mul(g.sigmoid(logit), recency);
  const int history = g.conv("history_color", info, history_color_, {}, 0, rgb, /*trainable=*/false);
  const int negated = g.affine("history_negate", image, negate_scale_, negate_shift_, /*trainable=*/false);
  return g.add(image, g.mul(weight, g.add(history, negated)));
}

torch::Tensor RitBlockImpl::skip_at_jitter(const torch::Tensor& image, const torch::Tensor& lr_color,
                                          const torch::Tensor& info) const {
  // The kernels and the operand order of describe_skip_at_jitter(), so both give the same bits.
  const auto at_jitter = graph::apply_sample(lr_color, torch::conv2d(info, jitter_offsets_), scale_,
                                             graph::ResizeMode::Bilinear);
  const auto unjittered = graph::apply_resize(lr_color, scale_, graph::ResizeMode::Bilinear);
  const auto negated = graph::apply_affine(unjittered, negate_scale_, negate_shift_);
  if (!hr_jitter_offsets_.defined()) return image + (at_jitter + negated);
  const auto residual = graph::apply_sample(image + negated, torch::conv2d(info, hr_jitter_offsets_), 1,
                                            graph::ResizeMode::Bilinear);
  return residual + at_jitter;
}

int RitBlockImpl::describe_skip_at_jitter(graph::Builder& g, int image, int lr_color, int info) const {
  const int offsets = g.conv("jitter_offsets", info, jitter_offsets_, {}, 0, graph::fixed_layout("jitter", 2),
                             /*trainable=*/false);
  const int at_jitter = g.sample(lr_color, offsets, graph::ResizeMode::Bilinear);
  const int unjittered = g.resize(lr_color, scale_, graph::ResizeMode::Bilinear);
  const int negated = g.affine("skip_negate", unjittered, negate_scale_, negate_shift_, /*trainable=*/false);
  if (!hr_jitter_offsets_.defined()) return g.add(image, g.add(at_jitter, negated));
  const int hr_offsets = g.conv("hr_jitter_offsets", info, hr_jitter_offsets_, {}, 0, graph::fixed_layout("jitter", 2),
                                /*trainable=*/false);
  const int residual = g.sample(g.add(image, negated), hr_offsets, graph::ResizeMode::Bilinear);
  return g.add(residual, at_jitter);
}

}  // namespace cgsr
