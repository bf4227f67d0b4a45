#include "render_data/bsp_channel.h"

#include <oneapi/tbb/parallel_for.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/error.h"
#include "core/tensor_checks.h"

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

}  // namespace

ResolvedBspBorder resolve_bsp_border(const torch::Tensor& lr_color, const BspBorderImage& image, int scale,
                                     const std::string& what) {
  if (lr_color.dim() != 3 || lr_color.size(0) != 3)
    throw Error(what, "the colour to resolve the BSP border image over must be [3,H,W], got " + shape_string(lr_color));
  if (scale < 1) throw Error(what, "scale must be >= 1, got " + std::to_string(scale));
  const int64_t h = lr_color.size(1), w = lr_color.size(2);
  if (image.width() != w || image.height() != h)
    throw Error(what, "BSP border image of " + std::to_string(image.width()) + "x" + std::to_string(image.height()) +
                          " for a frame of " + std::to_string(w) + "x" + std::to_string(h));
  const torch::Tensor in = lr_color.to(torch::kFloat32).contiguous();
  const int64_t H = h * scale, W = w * scale, plane = H * W;
  namespace F = torch::nn::functional;
  // The bicubic base: upscale_bicubic's call (eval/baselines/interpolation.h, which render_data
  // does not link); at scale 1 the image itself.
  ResolvedBspBorder out;
  out.color = scale == 1 ? in.clone()
                         : F::interpolate(in.unsqueeze(0), F::InterpolateFuncOptions()
                                                               .size(std::vector<int64_t>{H, W})
                                                               .mode(torch::kBicubic)
                                                               .align_corners(false))
                               .squeeze(0)
                               .contiguous();
  out.coverage = torch::zeros({1, H, W}, torch::kFloat32);
  if (image.size() == 0) return out;
  float* item = out.color.data_ptr<float>();
  float* covered = out.coverage.data_ptr<float>();
  const float* texels = in.data_ptr<float>();
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
        covered[Y * W + X] = 1.0f;
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
  return out;
}

torch::Tensor bsp_channel(const torch::Tensor& lr_color, const BspBorderImage& image, int scale, const std::string& what) {
  ResolvedBspBorder r = resolve_bsp_border(lr_color, image, scale, what);
  return torch::cat({r.color, r.coverage}, 0);
}

}  // namespace cgsr
