#include "render_data/edges.h"

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/error.h"

namespace cgsr {
namespace {

struct EdgeInput {
  int W = 0, H = 0;
  const float* w = nullptr;       // 1/z, 0 where there is no geometry
  const float* n = nullptr;       // 3 planes or null
  const int32_t* id = nullptr;    // or null
  float depth_threshold = 0, cos_crease = -2;
  DepthPrecision precision;
};

// Discontinuity between p = (y, x) and its neighbour q = p + (dy, dx) (dx, dy >= 0 pairs only,
// the caller symmetrises).
bool discontinuous(const EdgeInput& in, int y, int x, int dy, int dx) {
  const size_t plane = static_cast<size_t>(in.W) * in.H;
  const size_t p = static_cast<size_t>(y) * in.W + x, q = static_cast<size_t>(y + dy) * in.W + (x + dx);
  const float wp = in.w[p], wq = in.w[q];
  if ((wp > 0) != (wq > 0)) return true;
  if (!(wp > 0)) return false;  // both empty
  if (in.id && in.id[p] != in.id[q]) return true;
  if (in.n) {
    const float c = in.n[p] * in.n[q] + in.n[p + plane] * in.n[q + plane] + in.n[p + 2 * plane] * in.n[q + 2 * plane];
    if (c < in.cos_crease) return true;
  }
  // Linear extrapolation of 1/z from each side (first order at borders and next to empty pixels).
  const int by = y - dy, bx = x - dx, ay = y + 2 * dy, ax = x + 2 * dx;
  float pred_q = wp, pred_p = wq;
  if (by >= 0 && bx >= 0) {
    const float wb = in.w[static_cast<size_t>(by) * in.W + bx];
    if (wb > 0) pred_q = 2 * wp - wb;
  }
  if (ay < in.H && ax < in.W) {
    const float wa = in.w[static_cast<size_t>(ay) * in.W + ax];
    if (wa > 0) pred_p = 2 * wq - wa;
  }
  // Quantisation: w_q - (2 w_p - w_b) takes each value's storage error (under a step, rounded
  // or truncated) once, the middle one twice with the opposite sign, so it stays within 2 steps.
  const float w = std::max(wp, wq);
  const float tolerance = in.depth_threshold * w + static_cast<float>(2.01 * in.precision.step_at(w));
  return std::abs(wq - pred_q) > tolerance && std::abs(wp - pred_p) > tolerance;
}

}  // namespace

torch::Tensor detect_edges(const torch::Tensor& depth, const torch::Tensor& normal, const torch::Tensor& ids,
                           const EdgeSettings& settings, const DepthPrecision& precision) {
  const auto d = depth.dim() == 3 ? depth.squeeze(0) : depth;
  CGSR_CHECK(d.dim() == 2, "detect_edges needs an [H,W] depth map");
  const int H = static_cast<int>(d.size(0)), W = static_cast<int>(d.size(1));
  // 1/z: +inf and 0 (no geometry) both become 0.
  const auto inv = torch::where(d.isfinite() & (d > 0), torch::reciprocal(d.to(torch::kFloat32)),
                                torch::zeros({}, torch::kFloat32))
                       .contiguous();
  torch::Tensor n, id;
  EdgeInput in;
  in.W = W;
  in.H = H;
  in.w = inv.data_ptr<float>();
  in.depth_threshold = settings.depth_threshold;
  in.precision = precision;
  if (normal.defined()) {
    n = normal.to(torch::kFloat32).reshape({3, H, W}).contiguous();
    in.n = n.data_ptr<float>();
    in.cos_crease = std::cos(settings.crease_angle * 3.14159265358979f / 180.0f);
  }
  if (ids.defined() && settings.id_changes) {
    id = ids.to(torch::kInt32).reshape({H, W}).contiguous();
    in.id = id.data_ptr<int32_t>();
  }
  auto out = torch::zeros({1, H, W}, torch::kFloat32);
  float* e = out.data_ptr<float>();
  tbb::parallel_for(0, H, [&](int y) {
    for (int x = 0; x < W; ++x) {
      const float wp = in.w[static_cast<size_t>(y) * W + x];
      if (!(wp > 0)) continue;  // empty pixels are never edges
      bool edge = false;
      // Right and down neighbours: p is marked when it is nearer or tied (p is left/top).
      if (x + 1 < W && discontinuous(in, y, x, 0, 1)) edge |= wp >= in.w[static_cast<size_t>(y) * W + x + 1];
      if (!edge && y + 1 < H && discontinuous(in, y, x, 1, 0)) edge |= wp >= in.w[static_cast<size_t>(y + 1) * W + x];
      // Left and up neighbours: p is marked when strictly nearer.
      if (!edge && x > 0 && discontinuous(in, y, x - 1, 0, 1)) edge |= wp > in.w[static_cast<size_t>(y) * W + x - 1];
      if (!edge && y > 0 && discontinuous(in, y - 1, x, 1, 0)) edge |= wp > in.w[static_cast<size_t>(y - 1) * W + x];
      e[static_cast<size_t>(y) * W + x] = edge ? 1.0f : 0.0f;
    }
  });
  return out;
}

torch::Tensor dilate_edges(const torch::Tensor& edges) {
  CGSR_CHECK(edges.dim() == 2 || (edges.dim() == 3 && edges.size(0) == 1), "dilate_edges needs an [H,W] edge map");
  const int64_t H = edges.size(-2), W = edges.size(-1);
  // Bool and uint8 maps (what frames and masks hold) are read as bytes as they are; no torch
  // operation for them: its OpenMP workers would still be spinning while the TBB loop runs.
  const bool bytes = edges.scalar_type() == torch::kBool || edges.scalar_type() == torch::kUInt8;
  const auto in = bytes ? edges.contiguous() : (edges != 0).contiguous();
  auto out = torch::empty({H, W}, torch::kBool);
  const auto* e = reinterpret_cast<const uint8_t*>(in.data_ptr());
  // A bool is one byte holding 0 or 1: the rows are written as bytes.
  uint8_t* o = reinterpret_cast<uint8_t*>(out.data_ptr<bool>());
  // Separable: the maximum of the (clamped) rows above, at and below, then of its neighbours
  // along the row; both loops are plain byte ORs the compiler vectorizes.
  tbb::parallel_for(tbb::blocked_range<int64_t>(0, H), [&](const tbb::blocked_range<int64_t>& rows) {
    std::vector<uint8_t> column(W);
    for (int64_t y = rows.begin(); y < rows.end(); ++y) {
      const uint8_t* above = e + std::max<int64_t>(y - 1, 0) * W;
      const uint8_t* here = e + y * W;
      const uint8_t* below = e + std::min(y + 1, H - 1) * W;
      for (int64_t x = 0; x < W; ++x) column[x] = (above[x] | here[x] | below[x]) != 0;
      uint8_t* row = o + y * W;
      row[0] = column[0] | (W > 1 ? column[1] : 0);
      for (int64_t x = 1; x + 1 < W; ++x) row[x] = column[x - 1] | column[x] | column[x + 1];
      if (W > 1) row[W - 1] = column[W - 2] | column[W - 1];
    }
  });
  return out.view(edges.sizes());
}

}  // namespace cgsr
