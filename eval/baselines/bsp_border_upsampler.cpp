#include "eval/baselines/bsp_border_upsampler.h"

#include <torch/torch.h>

#include <vector>

#include "core/error.h"
#include "core/tensor_checks.h"
#include "render_data/bsp_channel.h"

namespace cgsr {
namespace {

void check_inputs(const torch::Tensor& lr, const std::vector<const BspBorderImage*>& bsp, int scale) {
  if (lr.dim() != 4 || lr.size(1) != 3) throw Error("bsp_border upsampler", "expected [N,3,H,W], got " + shape_string(lr));
  if (scale < 1) throw Error("bsp_border upsampler", "scale must be >= 1");
  const int64_t n = lr.size(0), h = lr.size(2), w = lr.size(3);
  if (static_cast<int64_t>(bsp.size()) != n)
    throw Error("bsp_border upsampler", std::to_string(bsp.size()) + " BSP border image(s) for " + std::to_string(n) +
                                            " frame(s): every frame needs its own (a data set rendered with bsp_border)");
  for (int64_t k = 0; k < n; ++k) {
    if (!bsp[k]) throw Error("bsp_border upsampler", "frame " + std::to_string(k) + " of the batch has no BSP border image");
    if (bsp[k]->width() != w || bsp[k]->height() != h)
      throw Error("bsp_border upsampler", "BSP border image of " + std::to_string(bsp[k]->width()) + "x" +
                                              std::to_string(bsp[k]->height()) + " for a frame of " + std::to_string(w) +
                                              "x" + std::to_string(h));
  }
}

}  // namespace

torch::Tensor upscale_bsp_border(const torch::Tensor& lr, const std::vector<const BspBorderImage*>& bsp, int scale) {
  check_inputs(lr, bsp, scale);
  // One item at a time through the resolver the `bsp` rendering channel uses (bsp_channel.h).
  std::vector<torch::Tensor> items;
  for (int64_t k = 0; k < lr.size(0); ++k)
    items.push_back(resolve_bsp_border(lr[k], *bsp[k], scale, "bsp_border upsampler").color);
  return torch::stack(items);
}

}  // namespace cgsr
