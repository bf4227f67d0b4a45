#pragma once
// SRPO (Gu et al. 2022, "Super-Resolution by Predicting Offsets: An Ultra-Efficient
// Super-Resolution Network for Rasterized Images"): a three-convolution network predicts, for
// every HR pixel, an offset Omega (dx, dy in LR pixels) naming the LR pixel to copy there, so
// jagged rasterized edges move to their HR place instead of being blurred; flat areas come from
// interpolation.
//   offsets   conv 5x5 3->16, ReLU, conv 5x5 16->16, ReLU (at LR: the features), nearest
//             upsampling by s (the HR features), conv 5x5 16->2 = Omega at HR (Sec. 3.1, Fig. 4)
//   projection P(I_LR, Omega): HR pixel p reads the LR image at (p + 0.5) / s - 0.5 + Omega(p),
//             borders clamped (graph op Sample); nearest (the position rounded half to even) at
//             inference, bilinear while training (nearest passes no gradient to Omega)
//   fusion    (Sec. 3.2) alpha = gauss3x3(sigma 1.5) * 1{round(Omega) != 0},
//             out = alpha * P + (1 - alpha) * interpolated
//
// Parameters: 8,434, the paper's count, at every scale (the paper keeps "the same architecture
// as the SR factor 2, only changing the upsampling to x3"): conv1 3*16*5*5 + 16 = 1,216,
// conv2 16*16*5*5 + 16 = 6,416, conv3 16*2*5*5 + 2 = 802. MACs per LR pixel: 1,200 + 6,400 at LR
// and s*s*800 at HR (x2: 10,800), plus s*s*27 for the fusion's Gaussian, a constant (no
// parameters).
//
// Training is self-supervised on the projection (Sec. 3.1): in train() mode forward() returns
// the bilinear projection P, the image the paper's loss compares with the HR frame. The fused
// image could not train the offsets: alpha has no gradient and is 0 wherever no offset rounds
// away from 0, i.e. everywhere at the start. In eval() mode forward() returns the fused image.
// The training graph (describe(true)) and the inference graph mirror the two.
//
// Where the paper is silent or cannot be followed to the letter:
//   - interpolation: bicubic (a = -0.75, the project's Resize) instead of Lanczos, which neither
//     ONNX Resize nor LibTorch has; it is the nearest exportable kernel with negative lobes
//   - 1{round(Omega) != 0} is per pixel: 1 when either component rounds away from 0 (the pixel
//     was moved), written as AnyAbsAbove(Omega, 0.5), exact for round-half-to-even
//   - the 3x3 Gaussian (sigma 1.5) is normalized to sum 1 and zero-padded (the Conv op's
//     padding): alpha fades at the frame border, where the interpolation takes over
//
// Elastic training, the search and pruning narrow conv1 and conv2 like any layer group (the
// offsets and the fusion are fixed axes); a run of all three on SRPO x2 finished (docs/results/srpo.md).
//
// Layer groups: conv1 (16), conv2 (16: the features). The RIT (CG-enhanced SRPO) joins the
// features at LR (after conv2's ReLU) and, for rit.source hr_fuse, the HR features after the
// upsampling (group conv2 at factor s). The geometry head reads the HR features. No blocks.

#include "models/backbone.h"
#include "models/backbone_registry.h"
#include "models/layers.h"

namespace cgsr {

class SrpoImpl : public BackboneImpl {
 public:
  explicit SrpoImpl(const ArchSpec& spec);
  ExtractedFeatures extract(const torch::Tensor& lr_color) override;
  Reconstruction reconstruct(const torch::Tensor& features, const torch::Tensor& skip, const HrFusion& at_hr) override;
  ExtractedPorts describe_extract(graph::Builder& g, int color) const override;
  ReconstructionPorts describe_reconstruct(graph::Builder& g, int features, int skip,
                                           const HrFusionPort& at_hr) const override;
  std::string feature_group() const override { return "conv2"; }
  int64_t feature_factor() const override { return 1; }
  std::string hr_feature_group() const override { return "conv2"; }
  std::string hr_fusion_group() const override { return "conv2"; }

  torch::nn::Conv2d conv1{nullptr}, conv2{nullptr}, conv3{nullptr};

 private:
  int64_t scale_;
  torch::Tensor blur_;                          // [3, 1, 3, 3]: the Gaussian, once per colour channel
  torch::Tensor complement_scale_, complement_shift_;  // 1 - alpha as alpha * -1 + 1
};

// Rounding Omega to the nearest integer changes it where |component| > 0.5 (half to even).
inline constexpr double kSrpoMovedThreshold = 0.5;

}  // namespace cgsr
