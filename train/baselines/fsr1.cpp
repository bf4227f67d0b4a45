#include "train/baselines/fsr1.h"

#include <torch/torch.h>

#include <cmath>

#include "core/error.h"
#include "core/tensor_checks.h"

namespace cgsr {
namespace {
using torch::Tensor;

// The cheap luma FSR uses for its analysis: only ratios and directions of it matter.
Tensor luma(const Tensor& rgb) {
  return 0.5 * rgb.select(1, 0) + rgb.select(1, 1) + 0.5 * rgb.select(1, 2);  // [N, H, W]
}

// Direction and edge length contributed by one of the four central texels, from its '+'
// neighbourhood (left, centre, right) and (up, centre, down), weighted bilinearly by `w`.
void accumulate_direction(const Tensor& left, const Tensor& up, const Tensor& centre, const Tensor& right,
                          const Tensor& down, const Tensor& w, Tensor& dir_x, Tensor& dir_y, Tensor& len) {
  auto axis = [&](const Tensor& before, const Tensor& after, Tensor& dir) {
    const auto grad = after - before;
    // How much the gradient reverses: |after - before| relative to the larger one-sided step.
    const auto step = torch::maximum((after - centre).abs(), (centre - before).abs());
    const auto ratio = torch::where(step > 0, grad.abs() / step.clamp_min(1e-12), torch::zeros_like(step)).clamp(0, 1);
    dir = dir + grad * w;
    len = len + ratio * ratio * w;
  };
  axis(left, right, dir_x);
  axis(up, down, dir_y);
}

// EASU for the output rows [row_begin, row_end).
Tensor easu_rows(const Tensor& lr, int scale, int64_t row_begin, int64_t row_end) {
  const int64_t h = lr.size(2), w = lr.size(3), out_w = w * scale;
  const auto opts = torch::TensorOptions().dtype(lr.scalar_type());
  // Input coordinates of the output pixel centres (DESIGN.md convention).
  const auto py = (torch::arange(row_begin, row_end, opts) + 0.5) / scale - 0.5;
  const auto px = (torch::arange(out_w, opts) + 0.5) / scale - 0.5;
  const auto fy = py.floor(), fx = px.floor();
  const auto ay = (py - fy).view({1, -1, 1}), ax = (px - fx).view({1, 1, -1});
  const auto iy0 = fy.to(torch::kLong), ix0 = fx.to(torch::kLong);

  // tap(dy, dx): input texel at (floor(py) + dy, floor(px) + dx), edges replicated. [N, 3, R, W]
  auto tap = [&](int dy, int dx) {
    const auto iy = (iy0 + dy).clamp(0, h - 1), ix = (ix0 + dx).clamp(0, w - 1);
    return lr.index_select(2, iy).index_select(3, ix);
  };
  //      b c
  //    e f g h        f is the texel at floor(p); f g j k surround the sample point.
  //    i j k l
  //      n o
  const Tensor b = tap(-1, 0), c = tap(-1, 1), e = tap(0, -1), f = tap(0, 0), g = tap(0, 1), hh = tap(0, 2),
               i = tap(1, -1), j = tap(1, 0), k = tap(1, 1), l = tap(1, 2), n = tap(2, 0), o = tap(2, 1);
  const Tensor lb = luma(b), lc = luma(c), le = luma(e), lf = luma(f), lg = luma(g), lh = luma(hh), li = luma(i),
               lj = luma(j), lk = luma(k), ll = luma(l), ln = luma(n), lo = luma(o);

  Tensor dir_x = torch::zeros_like(lf), dir_y = torch::zeros_like(lf), len = torch::zeros_like(lf);
  accumulate_direction(le, lb, lf, lg, lj, (1 - ax) * (1 - ay), dir_x, dir_y, len);
  accumulate_direction(lf, lc, lg, lh, lk, ax * (1 - ay), dir_x, dir_y, len);
  accumulate_direction(li, lf, lj, lk, ln, (1 - ax) * ay, dir_x, dir_y, len);
  accumulate_direction(lj, lg, lk, ll, lo, ax * ay, dir_x, dir_y, len);

  // Normalize the direction; a flat neighbourhood has none, so use the x axis.
  const auto dir2 = dir_x * dir_x + dir_y * dir_y;
  const auto flat = dir2 < 1.0 / 32768.0;
  const auto inv = torch::rsqrt(dir2.clamp_min(1.0 / 32768.0));
  dir_x = torch::where(flat, torch::ones_like(dir_x), dir_x * inv);
  dir_y = torch::where(flat, torch::zeros_like(dir_y), dir_y * inv);

  // Edge length in [0,1]: 0 = smooth, 1 = a clear edge. Stretch the kernel along the edge
  // (more on diagonals) and shrink it across; sharpen the lobe as the edge gets stronger.
  len = (0.5 * len).pow(2);
  const auto stretch = 1.0 / torch::maximum(dir_x.abs(), dir_y.abs());
  const auto len_x = 1 + (stretch - 1) * len;
  const auto len_y = 1 - 0.5 * len;
  const auto lobe = 0.5 + ((0.25 - 0.04) - 0.5) * len;
  const auto clip = 1.0 / lobe;

  Tensor acc = torch::zeros_like(f), weight_sum = torch::zeros_like(lf);
  auto add_tap = [&](const Tensor& colour, int dx, int dy) {
    const auto ox = dx - ax, oy = dy - ay;  // tap position relative to the sample point
    const auto vx = (ox * dir_x + oy * dir_y) * len_x;
    const auto vy = (-ox * dir_y + oy * dir_x) * len_y;
    const auto d2 = torch::minimum(vx * vx + vy * vy, clip);
    // Lanczos-2 approximated by a polynomial: base window times a lobe-shaped term.
    const auto base = 25.0 / 16.0 * (0.4 * d2 - 1).pow(2) - (25.0 / 16.0 - 1);
    const auto wt = base * (lobe * d2 - 1).pow(2);
    acc = acc + colour * wt.unsqueeze(1);
    weight_sum = weight_sum + wt;
  };
  add_tap(b, 0, -1);
  add_tap(c, 1, -1);
  add_tap(e, -1, 0);
  add_tap(f, 0, 0);
  add_tap(g, 1, 0);
  add_tap(hh, 2, 0);
  add_tap(i, -1, 1);
  add_tap(j, 0, 1);
  add_tap(k, 1, 1);
  add_tap(l, 2, 1);
  add_tap(n, 0, 2);
  add_tap(o, 1, 2);

  const auto out = acc / weight_sum.unsqueeze(1);
  // De-ringing: stay within the four texels around the sample point.
  const auto lo_rgb = torch::minimum(torch::minimum(f, g), torch::minimum(j, k));
  const auto hi_rgb = torch::maximum(torch::maximum(f, g), torch::maximum(j, k));
  return torch::minimum(torch::maximum(out, lo_rgb), hi_rgb);
}
}  // namespace

Tensor fsr1_easu(const Tensor& lr, int scale) {
  if (lr.dim() != 4 || lr.size(1) != 3) throw Error("FSR", "expected an RGB NCHW image, got " + shape_string(lr));
  if (scale < 1) throw Error("FSR", "scale must be >= 1");
  require_finite(lr, "FSR input");
  const auto input = lr.clamp(0.0, 1.0);
  const int64_t out_h = lr.size(2) * scale;
  // Work on bands of output rows so memory stays bounded at large frame sizes.
  const int64_t band = 64;
  std::vector<Tensor> bands;
  for (int64_t r = 0; r < out_h; r += band) bands.push_back(easu_rows(input, scale, r, std::min(out_h, r + band)));
  return torch::cat(bands, 2);
}

Tensor fsr1_rcas(const Tensor& image, double sharpness_stops) {
  const auto x = image.clamp(0.0, 1.0);
  const auto padded = torch::nn::functional::pad(
      x, torch::nn::functional::PadFuncOptions({1, 1, 1, 1}).mode(torch::kReplicate));
  const int64_t h = x.size(2), w = x.size(3);
  auto shifted = [&](int dy, int dx) { return padded.slice(2, 1 + dy, 1 + dy + h).slice(3, 1 + dx, 1 + dx + w); };
  const auto up = shifted(-1, 0), left = shifted(0, -1), right = shifted(0, 1), down = shifted(1, 0);
  const auto mn4 = torch::minimum(torch::minimum(up, left), torch::minimum(right, down));
  const auto mx4 = torch::maximum(torch::maximum(up, left), torch::maximum(right, down));
  // The most negative lobe that keeps the result within [0,1] given the neighbours' range.
  const auto hit_min = torch::minimum(mn4, x) / (4.0 * mx4).clamp_min(1e-6);
  const auto hit_max = (1.0 - torch::maximum(mx4, x)) / (4.0 * mn4 - 4.0).clamp_max(-1e-6);
  const auto lobe_rgb = torch::maximum(-hit_min, hit_max);
  const double limit = 0.25 - 1.0 / 16.0;
  const auto lobe = std::exp2(-sharpness_stops) *
                    std::get<0>(lobe_rgb.max(1, /*keepdim=*/true)).clamp_max(0.0).clamp_min(-limit);
  return ((lobe * (up + left + right + down) + x) / (4.0 * lobe + 1.0)).clamp(0.0, 1.0);
}

Tensor upscale_fsr1(const Tensor& lr, int scale, const Fsr1Options& options) {
  const auto upscaled = fsr1_easu(lr, scale);
  return options.sharpen ? fsr1_rcas(upscaled, options.sharpness_stops) : upscaled;
}

}  // namespace cgsr
