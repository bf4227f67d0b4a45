#pragma once
// EDSR-baseline (Lim et al. 2017): mean shift -> head conv 3x3 -> 16 residual blocks
// (conv-ReLU-conv, res_scale 1) -> body conv 3x3, plus the head output (features) ->
// pixel-shuffle upsampler (one conv + shuffle for x2 and x3, two x2 stages for x4) -> tail conv
// 3x3 -> mean shift back. 64 features; 1,369,859 / 1,554,499 / 1,517,571 parameters at
// x2 / x3 / x4. The mean shifts by the RGB mean (0.4488, 0.4371, 0.4040) are fixed 1x1 convs
// (identity weights, bias -/+ mean) as in the reference implementation: constants, no
// parameters, but their 9 weights count as MACs (the published MAC counts include them).
//
// Layer groups:
//   features      head, every block's conv2 and body_conv (one residual stream)
//   block<i>_mid  conv1 out -> conv2 in
//   up1           channels after the first pixel shuffle (the conv before it makes up1 x r*r)
//   up2           the second x2 stage at x4

#include <torch/nn/modules/container/modulelist.h>

#include "models/backbone.h"
#include "models/backbone_registry.h"
#include "models/layers.h"

namespace cgsr {

class EdsrBlockImpl : public torch::nn::Module {
 public:
  EdsrBlockImpl(int index, int64_t features, int64_t mid);
  torch::Tensor forward(const torch::Tensor& x);
  int describe(graph::Builder& g, int x) const;
  torch::nn::Conv2d conv1{nullptr}, conv2{nullptr};

 private:
  int index_;
};
TORCH_MODULE(EdsrBlock);

class EdsrImpl : public BackboneImpl {
 public:
  explicit EdsrImpl(const ArchSpec& spec);
  ExtractedFeatures extract(const torch::Tensor& lr_color) override;
  Reconstruction reconstruct(const torch::Tensor& features, const torch::Tensor& skip, const HrFusion& at_hr) override;
  ExtractedPorts describe_extract(graph::Builder& g, int color) const override;
  ReconstructionPorts describe_reconstruct(graph::Builder& g, int features, int skip,
                                           const HrFusionPort& at_hr) const override;
  std::string feature_group() const override { return "features"; }
  int64_t feature_factor() const override { return 1; }
  std::string hr_feature_group() const override { return upsample_.size() == 2 ? "up2" : "up1"; }
  std::string hr_fusion_group() const override { return upsample_.size() == 2 ? "up2" : "up1"; }

 private:
  std::vector<int64_t> stage_factors_;  // {2}, {3} or {2, 2}
  torch::Tensor shift_weight_;          // [3, 3, 1, 1] identity
  torch::Tensor mean_, neg_mean_;       // [3] biases of the mean shifts
  torch::nn::Conv2d head{nullptr}, body_conv{nullptr}, tail{nullptr};
  torch::nn::ModuleList blocks{nullptr};
  std::vector<torch::nn::Conv2d> upsample_;
};

}  // namespace cgsr
