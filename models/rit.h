#pragma once
// The rendering information transform (RIT) block of CGSR (Fig. 3 of the paper): turns the
// chosen rendering channels into features and fuses them into the backbone between feature
// extraction and reconstruction.
//
//   info [N, C, h, w] (source lr) or [N, C, s*h, s*w] (source hr_pooled: s x s average pooling)
//   -> gate: x[c] * R[c], the regularization layer; an L1 penalty on R lets training switch off
//      channels a scene does not need, which can then be left out of the spec
//   -> conv 3x3 (C -> width) -> LeakyReLU 0.2                       (layer group "rit")
//   -> bilinear upsampling to the feature map when it is at HR (SRCNN)
//   -> fusion:  concat: features + conv1x1(cat(features, rit))
//               add:    features + conv1x1(rit)
//
// The fusion conv starts at zero, so a network with a fresh RIT computes exactly what its
// backbone computes (x + 0 == x), and training starts from the pretrained behaviour.

#include <torch/nn/module.h>
#include <torch/nn/modules/conv.h>
#include <torch/types.h>

#include "models/arch_spec.h"
#include "models/graph.h"

namespace cgsr {

// The layout of a rendering-information tensor: one fixed segment per named channel.
graph::Layout info_layout(const std::vector<RenderChannel>& channels);

class RitBlockImpl : public torch::nn::Module {
 public:
  // `feature_group`/`feature_channels`/`feature_factor` describe the backbone's feature map.
  RitBlockImpl(const RitSpec& rit, int scale, std::string feature_group, int64_t feature_channels,
               int64_t feature_factor);

  torch::Tensor forward(const torch::Tensor& features, const torch::Tensor& info);
  // `info` is the graph input holding the rendering information.
  int describe(graph::Builder& g, int features, int info) const;

  // Resolution of the expected info tensor relative to LR: 1 (lr) or scale (hr_pooled).
  int64_t info_factor() const { return pool_factor_; }

  torch::Tensor gate;  // [C], R_i of the paper, initialized to 1
  torch::nn::Conv2d conv{nullptr}, fuse{nullptr};

 private:
  bool concat_;
  int64_t pool_factor_;     // 1 or scale
  int64_t upsample_factor_;  // 1 or the feature map's factor
  std::string feature_group_;
  std::vector<RenderChannel> channels_;
};
TORCH_MODULE(RitBlock);

}  // namespace cgsr
