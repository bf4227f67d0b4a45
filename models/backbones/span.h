#pragma once
// SPAN (Wan et al. 2024, "Swift Parameter-free Attention Network for Efficient Super-Resolution",
// first in the NTIRE 2024 efficient-SR challenge), as its reference implementation builds it:
//   (x - mean) * 255 -> conv_1 -> 6 SPABs -> conv_2 on the last block's output
//   -> conv_cat 1x1 over [conv_1 out, conv_2 out, block 1 out, the last block's first conv out]
//   -> upsampler: conv 3x3 to 3*s*s channels, pixel shuffle (the image; no interpolated skip).
// A SPAB: c1_r, SiLU, c2_r, SiLU, c3_r; then (c3 + x) * (sigmoid(c3) - 0.5), an attention
// without parameters.
// Every conv_1, c*_r and conv_2 is a re-parameterizable conv (models/reparameterization.h):
// trained as a 1x1 (x2 channels) -> 3x3 -> 1x1 chain plus a 1x1 skip, run as one 3x3 conv. In
// train() mode forward() runs the branches, in eval() mode their fold; training graphs keep the
// branches, inference graphs fold them.
// Deployed (folded) parameters with 48 features: 410,700 at x2, 426,288 at x4; 150,688 at x4
// with 28 features (the NTIRE 2024 entry).
//
// Layer groups:
//   features       conv_1 out and every block's c3_r out (the stream the attention multiplies)
//   block<i>_a     c1_r out (the last block's also feeds conv_cat)
//   block<i>_b     c2_r out
//   trunk          conv_2 out
//   fuse           conv_cat out: the features at the insertion point (the RIT joins here)
// A branch's inner channels (twice its input's, then twice its output's) belong to the channel
// they are twice of, like a pixel shuffle's r*r positions, so narrowing a group narrows them too.
// The upsampler's output is the image: there is no HR feature map, so SPAN takes no HR fusion
// (rit.source hr_fuse) and no geometry head. Subnets keep the first and the last block (conv_cat
// reads their values).

#include <torch/nn/modules/container/modulelist.h>

#include "models/backbone.h"
#include "models/backbone_registry.h"
#include "models/layers.h"

namespace cgsr {

// SPAN's Conv3XC: expand 1x1 (padding 1) -> spatial 3x3 (no padding) -> squeeze 1x1, plus skip 1x1.
class RepConvImpl : public torch::nn::Module {
 public:
  RepConvImpl(int64_t in, int64_t out, int64_t gain = 2);
  torch::Tensor forward(const torch::Tensor& x);
  // The branches; `out` is the output's layout (the inner layouts follow from the input's and it).
  int describe(graph::Builder& g, int x, const graph::Layout& out) const;
  torch::nn::Conv2d expand{nullptr}, spatial{nullptr}, squeeze{nullptr}, skip{nullptr};

 private:
  int64_t gain_;
};
TORCH_MODULE(RepConv);

class SpabImpl : public torch::nn::Module {
 public:
  SpabImpl(int index, int64_t features, int64_t a, int64_t b);
  struct Output {
    torch::Tensor out, first;  // the block's output, c1_r's output
  };
  Output forward(const torch::Tensor& x);
  struct Ports {
    int out = -1, first = -1;
  };
  Ports describe(graph::Builder& g, int x) const;
  RepConv c1_r{nullptr}, c2_r{nullptr}, c3_r{nullptr};

 private:
  int index_;
};
TORCH_MODULE(Spab);

class SpanImpl : public BackboneImpl {
 public:
  explicit SpanImpl(const ArchSpec& spec);
  ExtractedFeatures extract(const torch::Tensor& lr_color) override;
  Reconstruction reconstruct(const torch::Tensor& features, const torch::Tensor& skip, const HrFusion& at_hr) override;
  ExtractedPorts describe_extract(graph::Builder& g, int color) const override;
  ReconstructionPorts describe_reconstruct(graph::Builder& g, int features, int skip,
                                           const HrFusionPort& at_hr) const override;
  std::string feature_group() const override { return "fuse"; }
  int64_t feature_factor() const override { return 1; }
  std::string hr_feature_group() const override { return ""; }
  std::string hr_fusion_group() const override { return ""; }

 private:
  int64_t scale_;
  torch::Tensor input_scale_, input_shift_;  // (x - mean) * 255 as x * 255 + (-255 * mean)
  RepConv conv_1{nullptr}, conv_2{nullptr};
  torch::nn::ModuleList blocks{nullptr};
  torch::nn::Conv2d conv_cat{nullptr}, upsampler{nullptr};
};

}  // namespace cgsr
