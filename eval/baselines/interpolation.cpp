#include "eval/baselines/interpolation.h"

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/error.h"
#include "core/tensor_checks.h"

namespace cgsr {
namespace F = torch::nn::functional;

namespace {
void check_input(const torch::Tensor& lr, int scale) {
  if (lr.dim() != 4) throw Error("upscale", "expected NCHW, got " + shape_string(lr));
  if (scale < 1) throw Error("upscale", "scale must be >= 1");
}

double sinc(double x) {
  if (std::abs(x) < 1e-12) return 1.0;
  const double px = M_PI * x;
  return std::sin(px) / px;
}

// One axis of a separable resampling as a band: output j reads input first[j] + t with weight
// weight[j * taps + t], t < taps. Indices may fall outside [0, in_size): the caller replicates
// the edge there, which is what resampling_matrix does by folding those taps onto the edge.
template <typename T>
struct BandTaps {
  int64_t taps = 0;
  int64_t pad_before = 0, pad_after = 0;  // how far the band reaches outside the input
  std::vector<int64_t> first;
  std::vector<T> weight;
};

// The taps and normalization of resampling_matrix, without the dense matrix.
template <typename T>
BandTaps<T> band_taps(int64_t in_size, int64_t out_size, double support, const std::function<double(double)>& kernel) {
  const double ratio = static_cast<double>(in_size) / static_cast<double>(out_size);
  auto centre = [&](int64_t j) { return (j + 0.5) * ratio - 0.5; };
  BandTaps<T> b;
  b.first.resize(out_size);
  std::vector<int64_t> count(out_size);
  for (int64_t j = 0; j < out_size; ++j) {
    b.first[j] = static_cast<int64_t>(std::floor(centre(j) - support)) + 1;
    count[j] = static_cast<int64_t>(std::floor(centre(j) + support)) - b.first[j] + 1;
    b.taps = std::max(b.taps, count[j]);
  }
  b.weight.assign(out_size * b.taps, T(0));  // rows with fewer taps end in zero weights
  std::vector<double> w(b.taps);
  for (int64_t j = 0; j < out_size; ++j) {
    double total = 0;
    for (int64_t t = 0; t < count[j]; ++t) {
      w[t] = kernel(centre(j) - static_cast<double>(b.first[j] + t));
      total += w[t];
    }
    for (int64_t t = 0; t < count[j]; ++t) b.weight[j * b.taps + t] = static_cast<T>(w[t] / total);
    b.pad_before = std::max(b.pad_before, -b.first[j]);
    b.pad_after = std::max(b.pad_after, b.first[j] + b.taps - in_size);
  }
  return b;
}

// Vertical pass into a row padded with the replicated edge, then the horizontal pass from it,
// one output row at a time: no [out_h, in_w] intermediate and no dense matrix.
template <typename T>
void lanczos_planes(const T* in, T* out, int64_t planes, int64_t h, int64_t w, int64_t out_h, int64_t out_w,
                    const BandTaps<T>& rows, const BandTaps<T>& cols) {
  const int64_t padded_w = cols.pad_before + w + cols.pad_after;
  tbb::parallel_for(tbb::blocked_range<int64_t>(0, planes * out_h, 8), [&](const tbb::blocked_range<int64_t>& r) {
    std::vector<T> row(padded_w);
    std::vector<const T*> src(rows.taps);
    for (int64_t k = r.begin(); k != r.end(); ++k) {
      const int64_t plane = k / out_h, y = k % out_h;
      const T* image = in + plane * h * w;
      for (int64_t t = 0; t < rows.taps; ++t)
        src[t] = image + std::clamp<int64_t>(rows.first[y] + t, 0, h - 1) * w;
      const T* wy = &rows.weight[y * rows.taps];
      T* mid = row.data() + cols.pad_before;
      for (int64_t x = 0; x < w; ++x) mid[x] = wy[0] * src[0][x];
      for (int64_t t = 1; t < rows.taps; ++t) {
        const T* s = src[t];
        const T wt = wy[t];
        for (int64_t x = 0; x < w; ++x) mid[x] += wt * s[x];
      }
      std::fill(row.data(), mid, mid[0]);
      std::fill(mid + w, row.data() + padded_w, mid[w - 1]);

      T* dst = out + k * out_w;
      const T* base = row.data() + cols.pad_before;
      for (int64_t x = 0; x < out_w; ++x) {
        const T* s = base + cols.first[x];
        const T* wx = &cols.weight[x * cols.taps];
        T acc = 0;
        for (int64_t t = 0; t < cols.taps; ++t) acc += wx[t] * s[t];
        dst[x] = acc;
      }
    }
  });
}

template <typename T>
torch::Tensor lanczos(const torch::Tensor& lr, int scale, int lobes) {
  const auto in = lr.contiguous();
  const int64_t n = in.size(0), c = in.size(1), h = in.size(2), w = in.size(3);
  auto out = torch::empty({n, c, h * scale, w * scale}, in.options());
  if (out.numel() == 0) return out;
  const double a = lobes;
  auto kernel = [a](double x) { return std::abs(x) < a ? sinc(x) * sinc(x / a) : 0.0; };
  const auto rows = band_taps<T>(h, h * scale, a, kernel);
  const auto cols = band_taps<T>(w, w * scale, a, kernel);
  lanczos_planes<T>(in.data_ptr<T>(), out.data_ptr<T>(), n * c, h, w, h * scale, w * scale, rows, cols);
  return out;
}
}  // namespace

torch::Tensor upscale_nearest(const torch::Tensor& lr, int scale) {
  check_input(lr, scale);
  // For an integer scale, each output pixel centre falls inside exactly one input pixel.
  return lr.repeat_interleave(scale, 2).repeat_interleave(scale, 3);
}

torch::Tensor upscale_bilinear(const torch::Tensor& lr, int scale) {
  check_input(lr, scale);
  return F::interpolate(lr, F::InterpolateFuncOptions()
                                .size(std::vector<int64_t>{lr.size(2) * scale, lr.size(3) * scale})
                                .mode(torch::kBilinear)
                                .align_corners(false));
}

torch::Tensor upscale_bicubic(const torch::Tensor& lr, int scale) {
  check_input(lr, scale);
  return F::interpolate(lr, F::InterpolateFuncOptions()
                                .size(std::vector<int64_t>{lr.size(2) * scale, lr.size(3) * scale})
                                .mode(torch::kBicubic)
                                .align_corners(false));
}

torch::Tensor upscale_bicubic_jittered(const torch::Tensor& lr, int scale, const std::vector<std::array<double, 2>>& jitter) {
  check_input(lr, scale);
  if (static_cast<int64_t>(jitter.size()) != lr.size(0))
    throw Error("bicubic", "one jitter per item needed: " + std::to_string(lr.size(0)) + " items, " +
                               std::to_string(jitter.size()) + " jitters");
  const int64_t h = lr.size(2), w = lr.size(3), H = h * scale, W = w * scale;
  // grid_sample's coordinates (align_corners = false): -1 and 1 are the outer edges of the input.
  const auto normalized = [scale](int64_t out, int64_t in, double offset) {
    return (2 * ((torch::arange(out, torch::kFloat64) + 0.5) / scale + offset) / in - 1).to(torch::kFloat32);
  };
  std::vector<torch::Tensor> grids;
  for (const auto& j : jitter) {
    const auto gx = normalized(W, w, j[0]).view({1, W}).expand({H, W});
    const auto gy = normalized(H, h, j[1]).view({H, 1}).expand({H, W});
    grids.push_back(torch::stack({gx, gy}, -1));
  }
  // Bicubic (mode 2) with border padding (1), which clamps each tap and so replicates the edge as
  // upscale_bicubic does; the functional API of LibTorch 1.13 offers no bicubic mode.
  return torch::grid_sampler(lr.to(torch::kFloat32), torch::stack(grids), /*interpolation_mode=*/2,
                             /*padding_mode=*/1, /*align_corners=*/false);
}

torch::Tensor resampling_matrix(int64_t in_size, int64_t out_size, double support,
                                const std::function<double(double)>& kernel) {
  auto m = torch::zeros({out_size, in_size}, torch::kFloat64);
  auto a = m.accessor<double, 2>();
  const double ratio = static_cast<double>(in_size) / static_cast<double>(out_size);
  for (int64_t j = 0; j < out_size; ++j) {
    const double centre = (j + 0.5) * ratio - 0.5;  // input coordinate of this output sample
    const int64_t first = static_cast<int64_t>(std::floor(centre - support)) + 1;
    const int64_t last = static_cast<int64_t>(std::floor(centre + support));
    double total = 0;
    for (int64_t i = first; i <= last; ++i) {
      const double w = kernel(centre - static_cast<double>(i));
      const int64_t clamped = std::clamp<int64_t>(i, 0, in_size - 1);  // replicate the edge
      a[j][clamped] += w;
      total += w;
    }
    for (int64_t i = 0; i < in_size; ++i) a[j][i] /= total;
  }
  return m;
}

torch::Tensor upscale_lanczos(const torch::Tensor& lr, int scale, int lobes) {
  check_input(lr, scale);
  if (lobes < 1) throw Error("upscale", "Lanczos needs at least one lobe");
  if (!lr.is_floating_point()) throw Error("upscale", "Lanczos needs a floating-point image");
  if (!lr.device().is_cpu()) throw Error("upscale", "Lanczos needs a CPU tensor");
  if (lr.scalar_type() == torch::kFloat64) return lanczos<double>(lr, scale, lobes);
  // Half and bfloat16 are computed in float.
  return lanczos<float>(lr.to(torch::kFloat32), scale, lobes).to(lr.scalar_type());
}

}  // namespace cgsr
