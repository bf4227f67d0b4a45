#pragma once
// Image quality metrics on batched tensors (NCHW, or CHW for one image), values in [0,1].
//   PSNR: 10 log10(1 / MSE) on RGB (or BT.601 Y with y_channel); +inf for identical images.
//   SSIM: Wang et al. 2004 with an 11x11 Gaussian window (sigma 1.5), K1 0.01, K2 0.03, L = 1,
//         over the valid region (no padding), averaged over channels.
// Both accumulate in float64 (parallel over rows) and return one value per image. Non-finite
// input is an error.

#include <torch/types.h>

#include <nlohmann/json.hpp>
#include <string>

namespace cgsr {

struct QualityOptions {
  bool y_channel = false;  // compare luma only
  int crop_border = 0;     // pixels removed from each side before comparing
};

torch::Tensor psnr(const torch::Tensor& output, const torch::Tensor& reference, const QualityOptions& options = {});
torch::Tensor ssim(const torch::Tensor& output, const torch::Tensor& reference, const QualityOptions& options = {});

// JSON has no infinity: an infinite PSNR is written as null with "<key>_infinite": true.
void put_psnr(nlohmann::ordered_json& j, const std::string& key, double value);

}  // namespace cgsr
