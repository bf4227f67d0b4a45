#pragma once
// PAN (Zhao et al. 2020, "Efficient Image Super-Resolution Using Pixel Attention"):
//   conv_first 3x3 -> 16 SC-PA blocks -> trunk_conv 3x3, plus the conv_first output (features)
//   -> U-PA upsampling: nearest x s (two x2 stages for x4), conv 3x3, pixel attention, LeakyReLU,
//      HR conv 3x3, LeakyReLU -> conv_last 3x3, plus the bilinear-upsampled input.
// Published: nf 40, unf 24, 16 blocks of width 20 (reduction 2): 261,403 parameters at x2/x3,
// 272,419 at x4. LeakyReLU slope 0.2 throughout.
//
// Layer groups:
//   features         conv_first, every block's conv3 and trunk_conv (one residual stream)
//   block<i>_a       conv1_a out -> k1 in                     (upper branch)
//   block<i>_a_out   k1 out -> conv3 in (first part)
//   block<i>_b       conv1_b out -> pa_conv.k2 and .k3 in     (lower branch)
//   block<i>_att     pa_conv.k2 out (sigmoid) x k3 out -> k4 in (attention product)
//   block<i>_b_out   pa_conv.k4 out -> conv3 in (second part)
//   up1, hr1         upconv1 out (and att1, whose product ties it) / hr_conv1 out
//   up2, hr2         the second stage at x4

#include <torch/nn/modules/container/modulelist.h>

#include "models/backbone.h"
#include "models/backbone_registry.h"
#include "models/layers.h"

namespace cgsr {

// x * sigmoid(conv1x1(x)): PAN's pixel attention in the upsampler.
class PixelAttentionImpl : public torch::nn::Module {
 public:
  explicit PixelAttentionImpl(int64_t channels);
  torch::Tensor forward(const torch::Tensor& x);
  int describe(graph::Builder& g, int x, const std::string& group) const;
  torch::nn::Conv2d conv{nullptr};
};
TORCH_MODULE(PixelAttention);

// k4(k3(x) * sigmoid(k2(x))): the attention branch of an SC-PA block.
class PAConvImpl : public torch::nn::Module {
 public:
  PAConvImpl(int64_t in, int64_t att, int64_t out);
  torch::Tensor forward(const torch::Tensor& x);
  int describe(graph::Builder& g, int x, const std::string& att_group, const std::string& out_group) const;
  torch::nn::Conv2d k2{nullptr}, k3{nullptr}, k4{nullptr};
};
TORCH_MODULE(PAConv);

struct ScpaWidths {
  int64_t features = 40, a = 20, a_out = 20, b = 20, att = 20, b_out = 20;
};

// Self-calibrated block with pixel attention; residual around the whole block.
class ScpaBlockImpl : public torch::nn::Module {
 public:
  ScpaBlockImpl(int index, const ScpaWidths& widths);
  torch::Tensor forward(const torch::Tensor& x);
  int describe(graph::Builder& g, int x) const;
  torch::nn::Conv2d conv1_a{nullptr}, conv1_b{nullptr}, k1{nullptr}, conv3{nullptr};
  PAConv pa_conv{nullptr};

 private:
  int index_;
};
TORCH_MODULE(ScpaBlock);

class PanImpl : public BackboneImpl {
 public:
  explicit PanImpl(const ArchSpec& spec);
  ExtractedFeatures extract(const torch::Tensor& lr_color) override;
  Reconstruction reconstruct(const torch::Tensor& features, const torch::Tensor& skip, const HrFusion& at_hr) override;
  ExtractedPorts describe_extract(graph::Builder& g, int color) const override;
  ReconstructionPorts describe_reconstruct(graph::Builder& g, int features, int skip,
                                           const HrFusionPort& at_hr) const override;
  std::string feature_group() const override { return "features"; }
  int64_t feature_factor() const override { return 1; }
  std::string hr_feature_group() const override { return stages_ == 2 ? "hr2" : "hr1"; }
  std::string hr_fusion_group() const override { return stages_ == 2 ? "up2" : "up1"; }

 private:
  int scale_;
  graph::ResizeMode skip_mode_;  // the interpolation of the LR image added to the output
  int stages_;          // upsampling stages: 1 (x2, x3) or 2 (x4)
  int64_t stage_factor_;  // nearest factor per stage
  torch::nn::Conv2d conv_first{nullptr}, trunk_conv{nullptr}, conv_last{nullptr};
  torch::nn::ModuleList blocks{nullptr};
  torch::nn::Conv2d upconv1{nullptr}, hr_conv1{nullptr}, upconv2{nullptr}, hr_conv2{nullptr};
  PixelAttention att1{nullptr}, att2{nullptr};
};

}  // namespace cgsr
