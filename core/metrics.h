#pragma once
// Image quality metrics on batched tensors (NCHW, or CHW for one image), values in [0,1].
//   PSNR: 10 log10(1 / MSE) on RGB (or BT.601 Y with y_channel); +inf for identical images.
//   SSIM: Wang et al. 2004 with an 11x11 Gaussian window (sigma 1.5), K1 0.01, K2 0.03, L = 1,
//         over the valid region (no padding), averaged over channels (ssim_window.h, shared
//         with the SSIM training loss).
// Both accumulate in float64 (parallel over rows) and return one value per image. Non-finite
// input is an error.
//   Masked PSNR: the same PSNR over the pixels a mask selects, and over the other pixels (e.g.
//         geometry edges and the rest); the MSE averages over the selected pixels only.

#include <torch/types.h>

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace cgsr {

struct QualityOptions {
  bool y_channel = false;  // compare luma only
  int crop_border = 0;     // pixels removed from each side before comparing
};

torch::Tensor psnr(const torch::Tensor& output, const torch::Tensor& reference, const QualityOptions& options = {});
torch::Tensor ssim(const torch::Tensor& output, const torch::Tensor& reference, const QualityOptions& options = {});

// PSNR of one image inside and outside a pixel mask. A side that has no pixel left after the
// border crop is empty; a side without error is +inf (as psnr).
struct MaskedPsnr {
  std::optional<double> inside, outside;
  double inside_fraction = 0;  // share of the compared (cropped) pixels inside the mask
};
// mask: bool or uint8 (nonzero = inside) [H,W] or [1,H,W] at the images' size, shared by every
// image of the batch; cropped and read like the images. One result per image.
std::vector<MaskedPsnr> masked_psnr(const torch::Tensor& output, const torch::Tensor& reference,
                                    const torch::Tensor& mask, const QualityOptions& options = {});

// JSON has no infinity: an infinite PSNR is written as null with "<key>_infinite": true.
void put_psnr(nlohmann::ordered_json& j, const std::string& key, double value);

}  // namespace cgsr
