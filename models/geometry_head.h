#pragma once
// Training-only head of CGSR's joint loss: predicts the HR rendering information from the
// reconstruction features (the input of the backbone's last conv, at HR size):
//   conv 3x3 (F -> width) -> LeakyReLU 0.2 -> conv 3x3 (width -> C)       (layer group "geometry")
// It is never part of inference, export or complexity counts.

#include <torch/nn/module.h>
#include <torch/nn/modules/conv.h>

#include "models/arch_spec.h"
#include "models/graph.h"

namespace cgsr {

class GeometryHeadImpl : public torch::nn::Module {
 public:
  GeometryHeadImpl(int64_t in_channels, int64_t width, const std::vector<RenderChannel>& channels);
  torch::Tensor forward(const torch::Tensor& hr_features);  // [N, C, H, W]
  int describe(graph::Builder& g, int hr_features) const;
  torch::nn::Conv2d conv1{nullptr}, conv2{nullptr};

 private:
  std::vector<RenderChannel> channels_;
};
TORCH_MODULE(GeometryHead);

}  // namespace cgsr
