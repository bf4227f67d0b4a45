#include "eval/baselines/bsp_border_upsampler.h"

#include <oneapi/tbb/parallel_for.h>
#include <torch/torch.h>

#include "core/error.h"
#include "core/tensor_checks.h"
#include "eval/baselines/interpolation.h"

namespace cgsr {

torch::Tensor upscale_bsp_border(const torch::Tensor& lr, const std::vector<const BspBorderImage*>& bsp, int scale) {
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
  torch::Tensor out = upscale_bicubic(lr.to(torch::kFloat32), scale).contiguous();
  const int64_t H = h * scale, W = w * scale, plane = H * W;
  float* o = out.data_ptr<float>();
  for (int64_t k = 0; k < n; ++k) {
    const BspBorderImage& image = *bsp[k];
    float* item = o + k * 3 * plane;
    tbb::parallel_for(size_t(0), image.size(), [&](size_t i) {
      const int pixel = image.pixel(i);
      const int x = pixel % static_cast<int>(w), y = pixel / static_cast<int>(w);
      const BspTree& tree = image.tree(i);
      for (int dy = 0; dy < scale; ++dy)
        for (int dx = 0; dx < scale; ++dx) {
          const int64_t X = static_cast<int64_t>(x) * scale + dx, Y = static_cast<int64_t>(y) * scale + dy;
          // The output pixel's centre in input pixel coordinates.
          const Rgb8& c = tree.leaves[tree.leaf_at((X + 0.5) / scale, (Y + 0.5) / scale)];
          for (int ch = 0; ch < 3; ++ch) item[ch * plane + Y * W + X] = c[ch] / 255.0f;
        }
    });
  }
  return out;
}

}  // namespace cgsr
