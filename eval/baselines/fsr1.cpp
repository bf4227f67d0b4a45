#include "eval/baselines/fsr1.h"

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/error.h"
#include "core/tensor_checks.h"

// Both passes run per output row over contiguous NCHW planes, rows split across TBB threads. The
// arithmetic (operations and their order, in the input's precision) is that of the tensor
// formulation this replaced, so the results are the same.

// The per-pixel loops are also compiled for AVX2 (twice the SSE2 vector width, no FMA so the
// rounding is the same), picked at load time on CPUs that have it. Clang does not multiversion
// templates, so it builds SSE2 only.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define CGSR_FSR_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define CGSR_FSR_VECTOR_CLONES
#endif
// The pointers of these loops never alias (separate rows and scratch); without this the compiler
// gives up on vectorizing for the number of run-time overlap checks it would need.
#if defined(__clang__)
#define CGSR_FSR_NO_ALIAS _Pragma("clang loop vectorize(assume_safety)")
#elif defined(__GNUC__)
#define CGSR_FSR_NO_ALIAS _Pragma("GCC ivdep")
#else
#define CGSR_FSR_NO_ALIAS
#endif

namespace cgsr {
namespace {
using torch::Tensor;

template <typename T>
T clamp01(T v) {
  return std::min(std::max(v, T(0)), T(1));  // NaN stays NaN, as torch::clamp
}

// Input coordinate of an output pixel centre (docs/design.md convention), computed like
// (arange(n) + 0.5) / scale - 0.5 in T.
template <typename T>
T sample_coordinate(int64_t j, int scale) {
  return (static_cast<T>(j) + T(0.5)) / static_cast<T>(scale) - T(0.5);
}

// EASU reads, for each output x, the input columns floor(px) - 1 .. floor(px) + 2. Each input
// row is first "expanded" to one value per output column: expanded[x + (dx + 1) * scale] is the
// texel at column floor(px) + dx (edges replicated), because floor(p) moves by exactly one when x
// moves by `scale`. Then every tap of the 12-tap filter is a contiguous read at a fixed offset
// and the per-pixel loop vectorizes.
template <typename T>
struct EasuGeometry {
  int scale = 1;
  int64_t out_w = 0, expanded_w = 0;
  std::vector<T> ax;             // [out_w] fractional x of the sample point
  std::vector<int64_t> source;   // [expanded_w] input column of each expanded entry
  std::vector<T> ay;             // [out_h]
  std::vector<int64_t> iy0;      // [out_h] floor(py)

  EasuGeometry(int64_t h, int64_t w, int s) : scale(s), out_w(w * s), expanded_w(w * s + 3 * s) {
    ax.resize(out_w);
    source.assign(expanded_w, -1);
    for (int64_t x = 0; x < out_w; ++x) {
      const T px = sample_coordinate<T>(x, s), fx = std::floor(px);
      ax[x] = px - fx;
      for (int dx = -1; dx <= 2; ++dx) {
        const int64_t col = std::clamp<int64_t>(static_cast<int64_t>(fx) + dx, 0, w - 1);
        int64_t& slot = source[x + (dx + 1) * s];
        if (slot >= 0 && slot != col) throw Error("FSR", "internal: floor(px) does not step by one per scale pixels");
        slot = col;
      }
    }
    for (int64_t y = 0; y < h * s; ++y) {
      const T py = sample_coordinate<T>(y, s), fy = std::floor(py);
      ay.push_back(py - fy);
      iy0.push_back(static_cast<int64_t>(fy));
    }
  }
};

// Per-thread cache of expanded input rows (clamped R, G, B and luma). The four rows an output row
// needs are consecutive, so row r can live in slot r % 4 and s output rows in a row reuse them.
template <typename T>
class ExpandedRows {
 public:
  explicit ExpandedRows(const EasuGeometry<T>& g) : g_(g), data_(4 * 4 * g.expanded_w), key_(4, -1) {}

  // Planes 0..2 = clamped colour, 3 = luma, of input row `row` of image `image` (key = image row id).
  const T* get(const T* image, int64_t h, int64_t w, int64_t row, int64_t key) {
    const int64_t slot = row % 4;
    T* d = data_.data() + slot * 4 * g_.expanded_w;
    if (key_[slot] != key) {
      key_[slot] = key;
      const T* r = image + row * w;
      const T* gr = r + h * w;
      const T* b = gr + h * w;
      T* dr = d;
      T* dg = d + g_.expanded_w;
      T* db = d + 2 * g_.expanded_w;
      T* dl = d + 3 * g_.expanded_w;
      for (int64_t j = 0; j < g_.expanded_w; ++j) {
        const int64_t i = g_.source[j];
        const T cr = clamp01(r[i]), cg = clamp01(gr[i]), cb = clamp01(b[i]);
        dr[j] = cr;
        dg[j] = cg;
        db[j] = cb;
        dl[j] = T(0.5) * cr + cg + T(0.5) * cb;  // the cheap luma FSR analyses
      }
    }
    return d;
  }

 private:
  const EasuGeometry<T>& g_;
  std::vector<T> data_;
  std::vector<int64_t> key_;
};

// One axis of one central texel's contribution to the direction and the edge length: how much
// the luma gradient reverses, |after - before| relative to the larger one-sided step.
template <typename T>
inline void easu_axis(T before, T centre, T after, T w, T& dir, T& len) {
  const T grad = after - before;
  const T step = std::max(std::abs(after - centre), std::abs(centre - before));
  // Equal to clamp(where(step > 0, |grad| / max(step, 1e-12), 0), 0, 1) for finite input: step == 0
  // means grad == 0, and clamping the numerator to the denominator gives exactly 1 where the
  // quotient would exceed it. Written without branches, which keep the loop from vectorizing.
  const T denominator = std::max(step, T(1e-12));
  const T r = std::min(std::abs(grad), denominator) / denominator;
  dir = dir + grad * w;
  len = len + r * r * w;
}

// Tap layout (f is the texel at floor(p); f g j k surround the sample point):
//      b c
//    e f g h
//    i j k l
//      n o
constexpr int kEasuTaps = 12;
constexpr int kTapDx[kEasuTaps] = {0, 1, -1, 0, 1, 2, -1, 0, 1, 2, 0, 1};  // b c e f g h i j k l n o
constexpr int kTapDy[kEasuTaps] = {-1, -1, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2};
constexpr int64_t kEasuBlock = 256;  // columns per step: the scratch arrays stay in L1

template <typename T>
struct EasuScratch {
  std::vector<T> dir_x = std::vector<T>(kEasuBlock), dir_y = std::vector<T>(kEasuBlock),
                 len = std::vector<T>(kEasuBlock),
                 weight = std::vector<T>((kEasuTaps + 1) * kEasuBlock);  // 12 taps, then their sum
};

// EASU for one output row. Each step is a separate loop over x: loops without calls, branches or
// inner loops are what the compiler vectorizes.
template <typename T>
CGSR_FSR_VECTOR_CLONES void easu_row(const T* const rows[4], const T* ax_row, T ay, int s, int64_t out_w,
                                     T* const out[3], EasuScratch<T>& scratch) {
  // rows[dy + 1] holds 4 expanded planes (R, G, B, luma); tap dx of x is at x + (dx + 1) * s.
  const int64_t plane = out_w + 3 * s;
  auto tap = [&](int k, int p, int64_t x0) { return rows[kTapDy[k] + 1] + p * plane + (kTapDx[k] + 1) * s + x0; };
  const T one_minus_ay = T(1) - ay;
  T* dir_x = scratch.dir_x.data();
  T* dir_y = scratch.dir_y.data();
  T* len = scratch.len.data();
  T* weight = scratch.weight.data();
  for (int64_t x0 = 0; x0 < out_w; x0 += kEasuBlock) {
    const int64_t n = std::min(kEasuBlock, out_w - x0);
    const T* ax = ax_row + x0;
    {
      const T *lb = tap(0, 3, x0), *lc = tap(1, 3, x0), *le = tap(2, 3, x0), *lf = tap(3, 3, x0),
              *lg = tap(4, 3, x0), *lh = tap(5, 3, x0), *li = tap(6, 3, x0), *lj = tap(7, 3, x0),
              *lk = tap(8, 3, x0), *ll = tap(9, 3, x0), *ln = tap(10, 3, x0), *lo = tap(11, 3, x0);
CGSR_FSR_NO_ALIAS
      for (int64_t x = 0; x < n; ++x) {
        // Each of f g j k contributes from its '+' neighbourhood, weighted bilinearly.
        const T fx = ax[x];
        T dx = 0, dy = 0, l = 0;
        easu_axis(le[x], lf[x], lg[x], (T(1) - fx) * one_minus_ay, dx, l);
        easu_axis(lb[x], lf[x], lj[x], (T(1) - fx) * one_minus_ay, dy, l);
        easu_axis(lf[x], lg[x], lh[x], fx * one_minus_ay, dx, l);
        easu_axis(lc[x], lg[x], lk[x], fx * one_minus_ay, dy, l);
        easu_axis(li[x], lj[x], lk[x], (T(1) - fx) * ay, dx, l);
        easu_axis(lf[x], lj[x], ln[x], (T(1) - fx) * ay, dy, l);
        easu_axis(lj[x], lk[x], ll[x], fx * ay, dx, l);
        easu_axis(lg[x], lk[x], lo[x], fx * ay, dy, l);
        dir_x[x] = dx;
        dir_y[x] = dy;
        len[x] = l;
      }
    }
    // Normalize the direction; a flat neighbourhood has none, so use the x axis. sqrt may set
    // errno, which keeps this loop scalar; it is the only one.
    for (int64_t x = 0; x < n; ++x) {
      const T dir2 = dir_x[x] * dir_x[x] + dir_y[x] * dir_y[x];
      const T inv = T(1) / std::sqrt(std::max(dir2, T(1.0 / 32768.0)));
      const bool flat = dir2 < T(1.0 / 32768.0);
      dir_x[x] = flat ? T(1) : dir_x[x] * inv;
      dir_y[x] = flat ? T(0) : dir_y[x] * inv;
    }
CGSR_FSR_NO_ALIAS
    for (int64_t x = 0; x < n; ++x) {
      const T nx = dir_x[x], ny = dir_y[x];
      // Edge length in [0,1]: 0 = smooth, 1 = a clear edge. Stretch the kernel along the edge
      // (more on diagonals) and shrink it across; sharpen the lobe as the edge gets stronger.
      const T half = T(0.5) * len[x];
      const T l2 = half * half;
      const T stretch = T(1) / std::max(std::abs(nx), std::abs(ny));
      const T len_x = T(1) + (stretch - T(1)) * l2;
      const T len_y = T(1) - T(0.5) * l2;
      const T lobe = T(0.5) + T((0.25 - 0.04) - 0.5) * l2;
      const T clip = T(1) / lobe;
      T sum = 0;
#pragma GCC unroll 12
      for (int k = 0; k < kEasuTaps; ++k) {
        const T ox = T(kTapDx[k]) - ax[x], oy = T(kTapDy[k]) - ay;  // tap relative to the sample point
        const T vx = (ox * nx + oy * ny) * len_x;
        const T vy = (-ox * ny + oy * nx) * len_y;
        const T d2 = std::min(vx * vx + vy * vy, clip);
        // Lanczos-2 approximated by a polynomial: base window times a lobe-shaped term.
        const T a = T(0.4) * d2 - T(1), b = lobe * d2 - T(1);
        const T base = T(25.0 / 16.0) * (a * a) - T(25.0 / 16.0 - 1);
        const T wt = base * (b * b);
        weight[k * kEasuBlock + x] = wt;
        sum = sum + wt;
      }
      weight[kEasuTaps * kEasuBlock + x] = sum;
    }
    for (int c = 0; c < 3; ++c) {
      const T *t0 = tap(0, c, x0), *t1 = tap(1, c, x0), *t2 = tap(2, c, x0), *t3 = tap(3, c, x0),
              *t4 = tap(4, c, x0), *t5 = tap(5, c, x0), *t6 = tap(6, c, x0), *t7 = tap(7, c, x0),
              *t8 = tap(8, c, x0), *t9 = tap(9, c, x0), *t10 = tap(10, c, x0), *t11 = tap(11, c, x0);
      const T* w = weight;
      T* o = out[c] + x0;
CGSR_FSR_NO_ALIAS
      for (int64_t x = 0; x < n; ++x) {
        constexpr int64_t B = kEasuBlock;
        T acc = 0;
        acc = acc + t0[x] * w[0 * B + x];
        acc = acc + t1[x] * w[1 * B + x];
        acc = acc + t2[x] * w[2 * B + x];
        acc = acc + t3[x] * w[3 * B + x];
        acc = acc + t4[x] * w[4 * B + x];
        acc = acc + t5[x] * w[5 * B + x];
        acc = acc + t6[x] * w[6 * B + x];
        acc = acc + t7[x] * w[7 * B + x];
        acc = acc + t8[x] * w[8 * B + x];
        acc = acc + t9[x] * w[9 * B + x];
        acc = acc + t10[x] * w[10 * B + x];
        acc = acc + t11[x] * w[11 * B + x];
        const T v = acc / w[kEasuTaps * B + x];
        // De-ringing: stay within the four texels around the sample point (f g j k).
        const T lo = std::min(std::min(t3[x], t4[x]), std::min(t7[x], t8[x]));
        const T hi = std::max(std::max(t3[x], t4[x]), std::max(t7[x], t8[x]));
        o[x] = std::min(std::max(v, lo), hi);
      }
    }
  }
}

// Per-task state of EASU: the expanded input rows and the scratch of easu_row.
template <typename T>
class EasuRows {
 public:
  EasuRows(const EasuGeometry<T>& g, const T* src, int64_t h, int64_t w) : g_(g), src_(src), h_(h), w_(w), cache_(g) {}

  // Output row y of image b, into three channel rows.
  void row(int64_t b, int64_t y, T* const out[3]) {
    const T* image = src_ + b * 3 * h_ * w_;
    const T* rows[4];
    for (int dy = -1; dy <= 2; ++dy) {
      const int64_t r = std::clamp<int64_t>(g_.iy0[y] + dy, 0, h_ - 1);
      rows[dy + 1] = cache_.get(image, h_, w_, r, b * h_ + r);
    }
    easu_row<T>(rows, g_.ax.data(), g_.ay[y], g_.scale, g_.out_w, out, scratch_);
  }

 private:
  const EasuGeometry<T>& g_;
  const T* src_;
  int64_t h_, w_;
  ExpandedRows<T> cache_;
  EasuScratch<T> scratch_;
};

template <typename T>
Tensor easu(const Tensor& lr, int scale) {
  const auto in = lr.contiguous();
  const int64_t n = in.size(0), h = in.size(2), w = in.size(3), out_h = h * scale, out_w = w * scale;
  auto out = torch::empty({n, 3, out_h, out_w}, in.options());
  if (out.numel() == 0) return out;
  const EasuGeometry<T> g(h, w, scale);
  T* dst = out.data_ptr<T>();
  tbb::parallel_for(tbb::blocked_range<int64_t>(0, n * out_h, 4), [&](const tbb::blocked_range<int64_t>& range) {
    EasuRows<T> easu_rows(g, in.data_ptr<T>(), h, w);
    for (int64_t k = range.begin(); k != range.end(); ++k) {
      const int64_t b = k / out_h, y = k % out_h;
      T* o = dst + b * 3 * out_h * out_w + y * out_w;
      T* const out_rgb[3] = {o, o + out_h * out_w, o + 2 * out_h * out_w};
      easu_rows.row(b, y, out_rgb);
    }
  });
  return out;
}

// RCAS lobe of one channel: the most negative lobe that keeps the result within [0,1] given the
// range of the 4 neighbours. `row` is the centre row with one replicated texel on each side.
template <typename T>
CGSR_FSR_VECTOR_CLONES void rcas_lobe(const T* up, const T* row, const T* down, int64_t w, T* lobe) {
CGSR_FSR_NO_ALIAS
  for (int64_t x = 0; x < w; ++x) {
    const T u = clamp01(up[x]), l = clamp01(row[x]), c = clamp01(row[x + 1]), r = clamp01(row[x + 2]),
            d = clamp01(down[x]);
    const T mn4 = std::min(std::min(u, l), std::min(r, d));
    const T mx4 = std::max(std::max(u, l), std::max(r, d));
    const T hit_min = std::min(mn4, c) / std::max(T(4) * mx4, T(1e-6));
    const T hit_max = (T(1) - std::max(mx4, c)) / std::min(T(4) * mn4 - T(4), T(-1e-6));
    lobe[x] = std::max(-hit_min, hit_max);
  }
}

template <typename T>
CGSR_FSR_VECTOR_CLONES void rcas_apply(const T* up, const T* row, const T* down, const T* lobe, int64_t w, T* out) {
CGSR_FSR_NO_ALIAS
  for (int64_t x = 0; x < w; ++x) {
    const T u = clamp01(up[x]), l = clamp01(row[x]), c = clamp01(row[x + 1]), r = clamp01(row[x + 2]),
            d = clamp01(down[x]);
    out[x] = clamp01((lobe[x] * (u + l + r + d) + c) / (T(4) * lobe[x] + T(1)));
  }
}

// RCAS of one row of every channel. up[ch] and down[ch] are the neighbouring rows; centre[ch] is
// the row itself with one replicated texel on each side, so left and right are plain offsets.
template <typename T>
class RcasRow {
 public:
  RcasRow(int64_t channels, int64_t w, double sharpness_stops)
      : c_(channels), w_(w), strength_(static_cast<T>(std::exp2(-sharpness_stops))), lobe_(w), channel_lobe_(w) {}

  void operator()(const T* const* up, const T* const* centre, const T* const* down, T* const* out) {
    // One lobe for all channels: the largest (least sharpening) of theirs.
    rcas_lobe(up[0], centre[0], down[0], w_, lobe_.data());
    for (int64_t ch = 1; ch < c_; ++ch) {
      rcas_lobe(up[ch], centre[ch], down[ch], w_, channel_lobe_.data());
      for (int64_t x = 0; x < w_; ++x) lobe_[x] = std::max(lobe_[x], channel_lobe_[x]);
    }
    const T limit = T(0.25 - 1.0 / 16.0);
    for (int64_t x = 0; x < w_; ++x) lobe_[x] = strength_ * std::max(std::min(lobe_[x], T(0)), -limit);
    for (int64_t ch = 0; ch < c_; ++ch) rcas_apply(up[ch], centre[ch], down[ch], lobe_.data(), w_, out[ch]);
  }

 private:
  int64_t c_, w_;
  T strength_;
  std::vector<T> lobe_, channel_lobe_;
};

template <typename T>
Tensor rcas(const Tensor& image, double sharpness_stops) {
  const auto in = image.contiguous();
  const int64_t n = in.size(0), c = in.size(1), h = in.size(2), w = in.size(3);
  auto out = torch::empty_like(in);
  if (out.numel() == 0) return out;
  const T* src = in.data_ptr<T>();
  T* dst = out.data_ptr<T>();
  tbb::parallel_for(tbb::blocked_range<int64_t>(0, n * h, 8), [&](const tbb::blocked_range<int64_t>& range) {
    RcasRow<T> rcas_row(c, w, sharpness_stops);
    std::vector<T> padded(c * (w + 2));
    std::vector<const T*> up(c), centre(c), down(c);
    std::vector<T*> o(c);
    for (int64_t k = range.begin(); k != range.end(); ++k) {
      const int64_t b = k / h, y = k % h;
      for (int64_t ch = 0; ch < c; ++ch) {
        const T* plane = src + (b * c + ch) * h * w;
        const T* row = plane + y * w;
        T* p = padded.data() + ch * (w + 2);
        std::copy(row, row + w, p + 1);
        p[0] = row[0];
        p[w + 1] = row[w - 1];
        up[ch] = plane + std::max<int64_t>(y - 1, 0) * w;
        centre[ch] = p;
        down[ch] = plane + std::min<int64_t>(y + 1, h - 1) * w;
        o[ch] = dst + ((b * c + ch) * h + y) * w;
      }
      rcas_row(up.data(), centre.data(), down.data(), o.data());
    }
  });
  return out;
}

// EASU then RCAS without the full-size EASU image: each task keeps the last three EASU rows
// (edge-padded for RCAS) and computes the one or two rows above and below its band again.
template <typename T>
Tensor easu_rcas(const Tensor& lr, int scale, double sharpness_stops) {
  const auto in = lr.contiguous();
  const int64_t n = in.size(0), h = in.size(2), w = in.size(3), out_h = h * scale, out_w = w * scale;
  auto out = torch::empty({n, 3, out_h, out_w}, in.options());
  if (out.numel() == 0) return out;
  const EasuGeometry<T> g(h, w, scale);
  T* dst = out.data_ptr<T>();
  const int64_t padded_w = out_w + 2;
  tbb::parallel_for(tbb::blocked_range<int64_t>(0, n * out_h, 16), [&](const tbb::blocked_range<int64_t>& range) {
    EasuRows<T> easu_rows(g, in.data_ptr<T>(), h, w);
    RcasRow<T> rcas_row(3, out_w, sharpness_stops);
    std::vector<T> ring(3 * 3 * padded_w);  // [row % 3][channel][1 + out_w + 1]
    int64_t ring_key[3] = {-1, -1, -1};
    // EASU row y of image b, edge-padded, as three channel pointers to the padded rows.
    auto easu_row_at = [&](int64_t b, int64_t y, const T* channels[3]) {
      T* slot = ring.data() + (y % 3) * 3 * padded_w;
      if (ring_key[y % 3] != b * out_h + y) {
        ring_key[y % 3] = b * out_h + y;
        T* const rgb[3] = {slot + 1, slot + padded_w + 1, slot + 2 * padded_w + 1};
        easu_rows.row(b, y, rgb);
        for (T* p : rgb) {
          p[-1] = p[0];
          p[out_w] = p[out_w - 1];
        }
      }
      for (int ch = 0; ch < 3; ++ch) channels[ch] = slot + ch * padded_w;
    };
    for (int64_t k = range.begin(); k != range.end(); ++k) {
      const int64_t b = k / out_h, y = k % out_h;
      const T *up[3], *centre[3], *down[3];
      easu_row_at(b, std::max<int64_t>(y - 1, 0), up);
      easu_row_at(b, y, centre);
      easu_row_at(b, std::min<int64_t>(y + 1, out_h - 1), down);
      for (int ch = 0; ch < 3; ++ch) {
        up[ch] += 1;  // RCAS reads the rows above and below without padding
        down[ch] += 1;
      }
      T* o = dst + b * 3 * out_h * out_w + y * out_w;
      T* const out_rgb[3] = {o, o + out_h * out_w, o + 2 * out_h * out_w};
      rcas_row(up, centre, down, out_rgb);
    }
  });
  return out;
}

void check_easu_input(const Tensor& lr, int scale) {
  if (lr.dim() != 4 || lr.size(1) != 3) throw Error("FSR", "expected an RGB NCHW image, got " + shape_string(lr));
  if (scale < 1) throw Error("FSR", "scale must be >= 1");
  require_finite(lr, "FSR input");
  if (!lr.is_floating_point()) throw Error("FSR", "expected a floating-point image");
  if (!lr.device().is_cpu()) throw Error("FSR", "expected a CPU tensor");
}
}  // namespace

// Float and double are computed in their own precision; half and bfloat16 in float.

Tensor fsr1_easu(const Tensor& lr, int scale) {
  check_easu_input(lr, scale);
  if (lr.scalar_type() == torch::kFloat64) return easu<double>(lr, scale);
  return easu<float>(lr.to(torch::kFloat32), scale).to(lr.scalar_type());
}

Tensor fsr1_rcas(const Tensor& image, double sharpness_stops) {
  if (image.dim() != 4) throw Error("FSR", "expected an NCHW image, got " + shape_string(image));
  if (!image.is_floating_point()) throw Error("FSR", "expected a floating-point image");
  if (!image.device().is_cpu()) throw Error("FSR", "expected a CPU tensor");
  if (image.scalar_type() == torch::kFloat64) return rcas<double>(image, sharpness_stops);
  return rcas<float>(image.to(torch::kFloat32), sharpness_stops).to(image.scalar_type());
}

Tensor upscale_fsr1(const Tensor& lr, int scale, const Fsr1Options& options) {
  if (!options.sharpen) return fsr1_easu(lr, scale);
  check_easu_input(lr, scale);
  // The same result as fsr1_rcas(fsr1_easu(lr, scale), ...) in one pass.
  if (lr.scalar_type() == torch::kFloat64) return easu_rcas<double>(lr, scale, options.sharpness_stops);
  if (lr.scalar_type() == torch::kFloat32) return easu_rcas<float>(lr, scale, options.sharpness_stops);
  return fsr1_rcas(fsr1_easu(lr, scale), options.sharpness_stops);
}

}  // namespace cgsr

#undef CGSR_FSR_VECTOR_CLONES
#undef CGSR_FSR_NO_ALIAS
