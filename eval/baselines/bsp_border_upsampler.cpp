#include "eval/baselines/bsp_border_upsampler.h"

#include <oneapi/tbb/parallel_for.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/error.h"
#include "core/tensor_checks.h"
#include "eval/baselines/interpolation.h"

namespace cgsr {
namespace {

// Keys' cubic convolution weight (a = -0.75, as upscale_bicubic) of a tap at distance x.
double keys(double x) {
  constexpr double a = -0.75;
  x = std::abs(x);
  if (x <= 1) return ((a + 2) * x - (a + 3)) * x * x + 1;
  if (x < 2) return ((a * x - 5 * a) * x + 8 * a) * x - 4 * a;
  return 0;
}

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
  const int64_t n = lr.size(0), h = lr.size(2), w = lr.size(3);
  const torch::Tensor in = lr.to(torch::kFloat32).contiguous();
  torch::Tensor out = upscale_bicubic(in, scale).contiguous();
  const int64_t H = h * scale, W = w * scale, plane = H * W;
  float* o = out.data_ptr<float>();
  const float* src = in.data_ptr<float>();
  for (int64_t k = 0; k < n; ++k) {
    const BspBorderImage& image = *bsp[k];
    if (image.size() == 0) continue;
    float* item = o + k * 3 * plane;
    const float* texels = src + k * 3 * h * w;
    // Input pixels within 2 of a border pixel: the only ones whose output pixels' taps can touch one.
    std::vector<uint8_t> near(static_cast<size_t>(h * w), 0);
    for (size_t i = 0; i < image.size(); ++i) {
      const int64_t bx = image.pixel(i) % w, by = image.pixel(i) / w;
      for (int64_t y = std::max<int64_t>(0, by - 2); y <= std::min(h - 1, by + 2); ++y)
        for (int64_t x = std::max<int64_t>(0, bx - 2); x <= std::min(w - 1, bx + 2); ++x) near[y * w + x] = 1;
    }
    // Only output pixels whose 4x4 bicubic taps touch a border pixel change.
    tbb::parallel_for(int64_t(0), H, [&](int64_t Y) {
      const double py = (Y + 0.5) / scale;  // the output centre in input pixel coordinates
      const int64_t y0 = static_cast<int64_t>(std::floor(py - 0.5)) - 1;
      double wy[4];
      for (int t = 0; t < 4; ++t) wy[t] = keys(py - 0.5 - static_cast<double>(y0 + t));
      for (int64_t X = 0; X < W; ++X) {
        const double px = (X + 0.5) / scale;
        if (!near[(Y / scale) * w + X / scale]) continue;
        const int64_t x0 = static_cast<int64_t>(std::floor(px - 0.5)) - 1;
        // In a border pixel: the leaf the centre falls in.
        if (const BspTree* own = image.at(static_cast<int>(px), static_cast<int>(py))) {
          const Rgb8& c = own->leaves[own->leaf_at(px, py)];
          for (int ch = 0; ch < 3; ++ch) item[ch * plane + Y * W + X] = c[ch] / 255.0f;
          continue;
        }
        bool touches = false;
        for (int ty = 0; ty < 4 && !touches; ++ty)
          for (int tx = 0; tx < 4 && !touches; ++tx)
            touches = image.at(static_cast<int>(std::clamp<int64_t>(x0 + tx, 0, w - 1)),
                               static_cast<int>(std::clamp<int64_t>(y0 + ty, 0, h - 1))) != nullptr;
        if (!touches) continue;
        // Bicubic in which a border pixel's tap is the colour of its leaf on this centre's side of
        // its lines (they extend beyond it): no colour bleeds across an edge from a border pixel.
        double wx[4], sum[3] = {0, 0, 0};
        for (int t = 0; t < 4; ++t) wx[t] = keys(px - 0.5 - static_cast<double>(x0 + t));
        for (int ty = 0; ty < 4; ++ty) {
          const int64_t ty_c = std::clamp<int64_t>(y0 + ty, 0, h - 1);
          for (int tx = 0; tx < 4; ++tx) {
            const int64_t tx_c = std::clamp<int64_t>(x0 + tx, 0, w - 1);
            const double weight = wy[ty] * wx[tx];
            if (const BspTree* tree = image.at(static_cast<int>(tx_c), static_cast<int>(ty_c))) {
              const Rgb8& c = tree->leaves[tree->leaf_at(px, py)];
              for (int ch = 0; ch < 3; ++ch) sum[ch] += weight * (c[ch] / 255.0);
            } else {
              for (int ch = 0; ch < 3; ++ch) sum[ch] += weight * texels[ch * h * w + ty_c * w + tx_c];
            }
          }
        }
        for (int ch = 0; ch < 3; ++ch) item[ch * plane + Y * W + X] = static_cast<float>(sum[ch]);
      }
    });
  }
  return out;
}

}  // namespace cgsr
