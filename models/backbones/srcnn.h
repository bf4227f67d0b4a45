#pragma once
// SRCNN 9-5-5 (Dong et al. 2015) on the bicubic-upsampled input: conv 9x9 (64) - ReLU -
// conv 5x5 (32) - ReLU (features, at HR size) - conv 5x5 (reconstruction), zero same-padding.
// 57,281 parameters on the Y channel, 69,251 on RGB.
//
// Y mode (colors: y) follows the SR literature: the network sees BT.601 luma of the bicubic
// image (core/color.h rgb_to_y) and predicts luma; chroma stays bicubic. Both colour steps are
// fixed 1x1 convs (no parameters): rgb -> y, and [bicubic rgb, predicted y] -> rgb, which adds
// (y' - y) / (219/255) to every channel, the inverse BT.601 transform with chroma unchanged.
//
// Layer groups: conv1 (64), conv2 (32). No blocks.

#include "models/backbone.h"
#include "models/backbone_registry.h"
#include "models/layers.h"

namespace cgsr {

class SrcnnImpl : public BackboneImpl {
 public:
  explicit SrcnnImpl(const ArchSpec& spec);
  ExtractedFeatures extract(const torch::Tensor& lr_color) override;
  Reconstruction reconstruct(const torch::Tensor& features, const torch::Tensor& skip, const HrFusion& at_hr) override;
  ExtractedPorts describe_extract(graph::Builder& g, int color) const override;
  ReconstructionPorts describe_reconstruct(graph::Builder& g, int features, int skip,
                                           const HrFusionPort& at_hr) const override;
  std::string feature_group() const override { return "conv2"; }
  int64_t feature_factor() const override { return scale_; }
  std::string hr_feature_group() const override { return "conv2"; }
  std::string hr_fusion_group() const override { return "conv2"; }

 private:
  int64_t scale_;
  bool luma_;
  torch::Tensor to_y_weight_, to_y_bias_;      // [1, 3, 1, 1], [1]
  torch::Tensor merge_weight_, merge_bias_;    // [3, 4, 1, 1], [3]
  torch::nn::Conv2d conv1{nullptr}, conv2{nullptr}, conv3{nullptr};
};

}  // namespace cgsr
