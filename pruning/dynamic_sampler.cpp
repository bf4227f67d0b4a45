#include "pruning/dynamic_sampler.h"

#include <torch/torch.h>

#include <algorithm>

#include "core/error.h"
#include "core/tensor_checks.h"
#include "core/text.h"
#include "models/layers.h"

namespace cgsr {

config::Schema<SamplerOptions> sampler_schema() {
  config::Schema<SamplerOptions> s;
  s.field("channels", &SamplerOptions::channels,
          "rendering channels the samplers read, current and previous frame (depth, normal, normal_angle, edge, "
          "motion)")
      .check([](const std::vector<std::string>& v) { return !v.empty(); }, "needs at least one channel")
      .check(
          [](const std::vector<std::string>& v) {
            try {
              parse_channels(v);
              return true;
            } catch (const Error&) {
              return false;
            }
          },
          "must be distinct names of render_data/render_channels.h (depth, normal, normal_angle, edge, motion)");
  s.field("grid", &SamplerOptions::grid, "the rendering information is average-pooled to grid x grid").range(2, 256);
  s.field("width", &SamplerOptions::width, "hidden channels per unit").range(1, 256);
  return s;
}

torch::Tensor sampler_input(const torch::Tensor& info, const torch::Tensor& previous,
                            const std::vector<RenderChannel>& channels, int grid) {
  const int64_t c = total_width(channels);
  if (!info.defined() || info.dim() != 4 || info.size(1) != c)
    throw Error("dynamic sampler", "rendering information must be [N, " + std::to_string(c) + ", H, W] (" +
                                       join(channel_names(channels)) + "), got " +
                                       (info.defined() ? shape_string(info) : std::string("nothing")));
  if (previous.defined() && previous.sizes() != info.sizes())
    throw Error("dynamic sampler", "previous frame's rendering information is " + shape_string(previous) +
                                       ", the current frame's " + shape_string(info));
  // Motion in pixels -> fractions of the frame.
  auto scale = torch::ones({1, c, 1, 1});
  int64_t offset = 0;
  for (auto ch : channels) {
    if (ch == RenderChannel::Motion) {
      scale[0][offset][0][0] = 1.0 / static_cast<double>(info.size(3));
      scale[0][offset + 1][0][0] = 1.0 / static_cast<double>(info.size(2));
    }
    offset += channel_width(ch);
  }
  const auto pool = [&](const torch::Tensor& x) {
    auto scaled = x.to(torch::kFloat) * scale;
    // A pixel moving more than a frame width left the view: renderers report such motion
    // (disoccluded or far geometry) with huge values that would swamp the average.
    int64_t at = 0;
    for (auto ch : channels) {
      if (ch == RenderChannel::Motion) scaled.slice(1, at, at + 2).clamp_(-1.0, 1.0);
      at += channel_width(ch);
    }
    return torch::adaptive_avg_pool2d(scaled, {grid, grid});
  };
  const auto current = pool(info);
  const auto change = previous.defined() ? current - pool(previous) : torch::zeros_like(current);
  return torch::cat({current, change}, 1);
}

DynamicSamplersImpl::DynamicSamplersImpl(const SamplerOptions& options, std::vector<int> patterns)
    : options_(options), patterns_(std::move(patterns)) {
  CGSR_CHECK(!patterns_.empty(), "dynamic samplers need at least one unit");
  for (int k : patterns_) CGSR_CHECK(k >= 1, "every unit needs at least one pattern");
  in_channels_ = 2 * total_width(options_.render_channels());
  const int64_t u = static_cast<int64_t>(patterns_.size()), w = options_.width;
  ParameterBudget::charge_conv(in_channels_, u * w, 3, 1, /*bias=*/true);
  ParameterBudget::charge_conv(u * w, u * w, 3, u, /*bias=*/true);
  conv1 = register_module("conv1", torch::nn::Conv2d(torch::nn::Conv2dOptions(in_channels_, u * w, 3).padding(1)));
  conv2 = register_module("conv2", torch::nn::Conv2d(torch::nn::Conv2dOptions(u * w, u * w, 3).padding(1).groups(u)));
  build_head();
}

void DynamicSamplersImpl::build_head() {
  const int64_t u = static_cast<int64_t>(patterns_.size()), w = options_.width;
  const int64_t k = *std::max_element(patterns_.begin(), patterns_.end());
  ParameterBudget::charge_conv(u * w, u * k, 1, u, /*bias=*/true);
  auto fresh = torch::nn::Conv2d(torch::nn::Conv2dOptions(u * w, u * k, 1).groups(u));
  if (head.is_empty()) {
    head = register_module("head", fresh);
  } else {
    head = replace_module("head", fresh);
  }
  invalid_ = torch::zeros({1, u, k});
  for (int64_t i = 0; i < u; ++i) invalid_[0][i].slice(0, patterns_[i]).fill_(-1e9);
}

torch::Tensor DynamicSamplersImpl::forward(const torch::Tensor& input) {
  if (input.dim() != 4 || input.size(1) != in_channels_)
    throw Error("dynamic sampler", "input must be [N, " + std::to_string(in_channels_) + ", g, g], got " +
                                       shape_string(input));
  auto x = torch::relu(conv1(input));
  x = torch::avg_pool2d(x, 2, 2, 0, /*ceil_mode=*/true);
  x = torch::adaptive_avg_pool2d(torch::relu(conv2(x)), {1, 1});
  const int64_t u = static_cast<int64_t>(patterns_.size());
  return head(x).view({input.size(0), u, -1}) + invalid_;
}

std::vector<std::vector<int>> DynamicSamplersImpl::choose(const torch::Tensor& input) {
  torch::NoGradGuard no_grad;
  const auto best = forward(input).argmax(2).to(torch::kLong).contiguous();
  std::vector<std::vector<int>> out(best.size(0), std::vector<int>(best.size(1)));
  const int64_t* p = best.data_ptr<int64_t>();
  for (int64_t n = 0; n < best.size(0); ++n)
    for (int64_t i = 0; i < best.size(1); ++i) out[n][i] = static_cast<int>(p[n * best.size(1) + i]);
  return out;
}

void DynamicSamplersImpl::keep_patterns(const std::vector<std::vector<int>>& kept) {
  CGSR_CHECK(kept.size() == patterns_.size(), "keep_patterns: one list per unit");
  const int64_t old_k = head->weight.size(0) / static_cast<int64_t>(patterns_.size());
  const auto old_weight = head->weight.detach().clone(), old_bias = head->bias.detach().clone();
  for (size_t i = 0; i < kept.size(); ++i) {
    CGSR_CHECK(!kept[i].empty(), "keep_patterns: a unit must keep a pattern");
    for (int k : kept[i]) CGSR_CHECK(k >= 0 && k < patterns_[i], "keep_patterns: pattern index out of range");
    patterns_[i] = static_cast<int>(kept[i].size());
  }
  build_head();
  torch::NoGradGuard no_grad;
  const int64_t new_k = head->weight.size(0) / static_cast<int64_t>(patterns_.size());
  head->weight.zero_();
  head->bias.zero_();
  for (size_t i = 0; i < kept.size(); ++i)
    for (size_t j = 0; j < kept[i].size(); ++j) {
      const int64_t to = static_cast<int64_t>(i) * new_k + static_cast<int64_t>(j);
      const int64_t from = static_cast<int64_t>(i) * old_k + kept[i][j];
      head->weight[to].copy_(old_weight[from]);
      head->bias[to].copy_(old_bias[from]);
    }
}

int64_t DynamicSamplersImpl::parameter_count() const {
  int64_t n = 0;
  for (const auto& p : parameters()) n += p.numel();
  return n;
}

int64_t DynamicSamplersImpl::macs() const {
  const int64_t g = options_.grid, half = (g + 1) / 2;
  return conv1->weight.numel() * g * g + conv2->weight.numel() * half * half + head->weight.numel();
}

}  // namespace cgsr
