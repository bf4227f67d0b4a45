#include "core/metrics.h"

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_reduce.h>

#include <array>
#include <cmath>
#include <functional>
#include <vector>

#include "core/color.h"
#include "core/config.h"
#include "core/error.h"
#include "core/ssim_window.h"
#include "core/tensor_checks.h"

namespace cgsr {
namespace {
constexpr int kWindow = ssim_window::kSize;

// Validates the pair and returns both as contiguous NCHW, float64 inputs as they are and
// everything else as float32, after the Y conversion and border crop. Finiteness is checked by
// the loops that read them.
std::pair<torch::Tensor, torch::Tensor> prepare(const torch::Tensor& output, const torch::Tensor& reference,
                                                const QualityOptions& options, const char* metric) {
  if (!output.sizes().equals(reference.sizes()))
    throw Error(metric, "shapes differ: " + shape_string(output) + " vs " + shape_string(reference));
  if (output.dim() != 3 && output.dim() != 4)
    throw Error(metric, "expected CHW or NCHW, got shape " + shape_string(output));
  const auto type = output.scalar_type() == torch::kFloat64 && reference.scalar_type() == torch::kFloat64
                        ? torch::kFloat64
                        : torch::kFloat32;
  auto a = (output.dim() == 3 ? output.unsqueeze(0) : output).to(type);
  auto b = (reference.dim() == 3 ? reference.unsqueeze(0) : reference).to(type);
  if (options.y_channel) {
    a = rgb_to_y(a);
    b = rgb_to_y(b);
  }
  const int64_t crop = options.crop_border;
  if (crop < 0) throw Error(metric, "crop_border " + config::out_of_range(static_cast<double>(crop), 0, config::kUnbounded));
  if (crop > 0) {
    if (a.size(2) <= 2 * crop || a.size(3) <= 2 * crop)
      throw Error(metric, "crop_border " + std::to_string(crop) + " leaves nothing of a " +
                              std::to_string(a.size(3)) + "x" + std::to_string(a.size(2)) + " image");
    a = a.slice(2, crop, a.size(2) - crop).slice(3, crop, a.size(3) - crop);
    b = b.slice(2, crop, b.size(2) - crop).slice(3, crop, b.size(3) - crop);
  }
  return {a.contiguous(), b.contiguous()};
}

[[noreturn]] void non_finite(const char* metric) {
  throw Error(std::string(metric) + " input", "contains NaN or infinite values");
}

// Mean SSIM of one plane over its valid region. Output rows are independent: each computes the
// five Gaussian-weighted local statistics (means, second moments, cross moment) of its 11 input
// rows in float64, first down the columns, then along the row (the separable window: 22 instead
// of 121 multiply-adds per pixel and statistic). Returns NaN for non-finite input.
template <class T>
double plane_ssim(const T* a, const T* b, int64_t h, int64_t w) {
  static const std::array<double, kWindow> g = ssim_window::gaussian_1d();
  const int64_t out_h = h - kWindow + 1, out_w = w - kWindow + 1;
  return tbb::parallel_reduce(
      tbb::blocked_range<int64_t>(0, out_h), 0.0,
      [&](const tbb::blocked_range<int64_t>& rows, double sum) {
        std::vector<double> col(5 * static_cast<size_t>(w));
        double *ma = col.data(), *mb = ma + w, *saa = mb + w, *sbb = saa + w, *sab = sbb + w;
        for (int64_t y = rows.begin(); y < rows.end(); ++y) {
          std::fill(col.begin(), col.end(), 0.0);
          for (int k = 0; k < kWindow; ++k) {
            const T* ra = a + (y + k) * w;
            const T* rb = b + (y + k) * w;
            const double gk = g[k];
            for (int64_t x = 0; x < w; ++x) {
              const double va = ra[x], vb = rb[x];
              ma[x] += gk * va;
              mb[x] += gk * vb;
              saa[x] += gk * va * va;
              sbb[x] += gk * vb * vb;
              sab[x] += gk * va * vb;
            }
          }
          for (int64_t x = 0; x < out_w; ++x) {
            double mu_a = 0, mu_b = 0, e_aa = 0, e_bb = 0, e_ab = 0;
            for (int k = 0; k < kWindow; ++k) {
              mu_a += g[k] * ma[x + k];
              mu_b += g[k] * mb[x + k];
              e_aa += g[k] * saa[x + k];
              e_bb += g[k] * sbb[x + k];
              e_ab += g[k] * sab[x + k];
            }
            sum += ssim_window::from_moments(mu_a, mu_b, e_aa, e_bb, e_ab);
          }
        }
        return sum;
      },
      std::plus<double>()) /
         static_cast<double>(out_h * out_w);
}

template <class T>
double sum_squared_error(const T* a, const T* b, int64_t count) {
  return tbb::parallel_reduce(
      tbb::blocked_range<int64_t>(0, count, 1 << 16), 0.0,
      [&](const tbb::blocked_range<int64_t>& r, double sum) {
        for (int64_t k = r.begin(); k < r.end(); ++k) {
          const double d = static_cast<double>(a[k]) - static_cast<double>(b[k]);
          sum += d * d;  // NaN or inf in either image makes d, and so the sum, non-finite
        }
        return sum;
      },
      std::plus<double>());
}

struct SplitError {
  double inside = 0, outside = 0;
  int64_t inside_pixels = 0;
};

// Squared error of one image (c planes of h x w) split by a mask of h x w bytes (nonzero =
// inside) whose rows are `mask_stride` apart, parallel over rows.
template <class T>
SplitError masked_squared_error(const T* a, const T* b, const uint8_t* mask, int64_t mask_stride, int64_t c,
                                int64_t h, int64_t w) {
  return tbb::parallel_reduce(
      tbb::blocked_range<int64_t>(0, h), SplitError{},
      [&](const tbb::blocked_range<int64_t>& rows, SplitError sum) {
        // Per row: the squared error summed over channels into a buffer (a loop without a
        // reduction, which the compiler vectorizes), then one pass splitting it by the mask.
        // Local accumulators: the uint8 mask may alias anything, so sums kept in `sum` would be
        // stored and reloaded at every pixel.
        std::vector<double> error(static_cast<size_t>(w));
        double inside = 0, outside = 0;
        int64_t pixels = 0;
        for (int64_t y = rows.begin(); y < rows.end(); ++y) {
          std::fill(error.begin(), error.end(), 0.0);
          double* e = error.data();
          for (int64_t ch = 0; ch < c; ++ch) {
            const T* ra = a + (ch * h + y) * w;
            const T* rb = b + (ch * h + y) * w;
            for (int64_t x = 0; x < w; ++x) {
              const double d = static_cast<double>(ra[x]) - static_cast<double>(rb[x]);
              e[x] += d * d;
            }
          }
          const uint8_t* m = mask + y * mask_stride;
          for (int64_t x = 0; x < w; ++x) {
            if (m[x]) {
              inside += e[x];
              ++pixels;
            } else {
              outside += e[x];
            }
          }
        }
        sum.inside += inside;
        sum.outside += outside;
        sum.inside_pixels += pixels;
        return sum;
      },
      [](SplitError l, const SplitError& r) {
        l.inside += r.inside;
        l.outside += r.outside;
        l.inside_pixels += r.inside_pixels;
        return l;
      });
}

std::optional<double> psnr_of(double sse, int64_t count) {
  if (count == 0) return std::nullopt;
  return -10.0 * std::log10(sse / static_cast<double>(count));  // mse = 0 gives +inf
}
}  // namespace

torch::Tensor psnr(const torch::Tensor& output, const torch::Tensor& reference, const QualityOptions& options) {
  const auto [a, b] = prepare(output, reference, options, "PSNR");
  const int64_t n = a.size(0), per_image = a.numel() / std::max<int64_t>(1, n);
  auto out = torch::empty({n}, torch::kFloat64);
  for (int64_t i = 0; i < n; ++i) {
    const double sse = a.scalar_type() == torch::kFloat64
                           ? sum_squared_error(a.data_ptr<double>() + i * per_image, b.data_ptr<double>() + i * per_image, per_image)
                           : sum_squared_error(a.data_ptr<float>() + i * per_image, b.data_ptr<float>() + i * per_image, per_image);
    if (!std::isfinite(sse)) non_finite("PSNR");
    out[i] = -10.0 * std::log10(sse / static_cast<double>(per_image));  // mse = 0 gives +inf
  }
  return out;
}

torch::Tensor ssim(const torch::Tensor& output, const torch::Tensor& reference, const QualityOptions& options) {
  const auto [a, b] = prepare(output, reference, options, "SSIM");
  const int64_t n = a.size(0), c = a.size(1), h = a.size(2), w = a.size(3);
  if (h < kWindow || w < kWindow)
    throw Error("SSIM", "needs images of at least 11x11 pixels (after cropping), got " + std::to_string(w) + "x" +
                            std::to_string(h));
  auto out = torch::empty({n}, torch::kFloat64);
  for (int64_t i = 0; i < n; ++i) {
    double sum = 0;
    for (int64_t ch = 0; ch < c; ++ch) {
      const int64_t offset = (i * c + ch) * h * w;
      sum += a.scalar_type() == torch::kFloat64 ? plane_ssim(a.data_ptr<double>() + offset, b.data_ptr<double>() + offset, h, w)
                                                : plane_ssim(a.data_ptr<float>() + offset, b.data_ptr<float>() + offset, h, w);
    }
    if (!std::isfinite(sum)) non_finite("SSIM");
    out[i] = sum / static_cast<double>(c);
  }
  return out;
}

std::vector<MaskedPsnr> masked_psnr(const torch::Tensor& output, const torch::Tensor& reference,
                                    const torch::Tensor& mask, const QualityOptions& options) {
  const auto [a, b] = prepare(output, reference, options, "masked PSNR");
  if (!(mask.dim() == 2 || (mask.dim() == 3 && mask.size(0) == 1)) || mask.size(-2) != output.size(-2) ||
      mask.size(-1) != output.size(-1))
    throw Error("masked PSNR", "the mask must be [H,W] or [1,H,W] at the images' size " + shape_string(output) +
                                   ", got " + shape_string(mask));
  if (mask.scalar_type() != torch::kBool && mask.scalar_type() != torch::kUInt8)
    throw Error("masked PSNR", std::string("the mask must be bool or uint8, got ") + c10::toString(mask.scalar_type()));
  // Both types are one byte per pixel: the loops read the bytes and crop by offset. (No torch
  // operation here: its OpenMP workers would still be spinning while the TBB loop runs.)
  const auto m = mask.contiguous();
  const int64_t crop = options.crop_border, stride = mask.size(-1);  // prepare() checked the crop
  const auto* bytes = reinterpret_cast<const uint8_t*>(m.data_ptr()) + crop * stride + crop;
  const int64_t n = a.size(0), c = a.size(1), h = a.size(2), w = a.size(3);
  std::vector<MaskedPsnr> out(n);
  for (int64_t i = 0; i < n; ++i) {
    const int64_t offset = i * c * h * w;
    const SplitError e =
        a.scalar_type() == torch::kFloat64
            ? masked_squared_error(a.data_ptr<double>() + offset, b.data_ptr<double>() + offset, bytes, stride, c, h, w)
            : masked_squared_error(a.data_ptr<float>() + offset, b.data_ptr<float>() + offset, bytes, stride, c, h, w);
    if (!std::isfinite(e.inside) || !std::isfinite(e.outside)) non_finite("masked PSNR");
    out[i].inside = psnr_of(e.inside, e.inside_pixels * c);
    out[i].outside = psnr_of(e.outside, (h * w - e.inside_pixels) * c);
    out[i].inside_fraction = static_cast<double>(e.inside_pixels) / static_cast<double>(h * w);
  }
  return out;
}

void put_psnr(nlohmann::ordered_json& j, const std::string& key, double value) {
  if (std::isinf(value) && value > 0) {
    j[key] = nullptr;
    j[key + "_infinite"] = true;
  } else {
    j[key] = value;
  }
}

}  // namespace cgsr
