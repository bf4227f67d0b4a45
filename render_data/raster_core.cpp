#include "render_data/raster_core.h"

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"

namespace cgsr {
namespace {

// A vertex during clipping: clip-space position, depth attribute, original barycentrics.
struct ClipVertex {
  Vec4 clip;
  float depth;
  float bary[3];
};

ClipVertex lerp_vertex(const ClipVertex& a, const ClipVertex& b, float t) {
  ClipVertex r;
  r.clip = {a.clip.x + (b.clip.x - a.clip.x) * t, a.clip.y + (b.clip.y - a.clip.y) * t,
            a.clip.z + (b.clip.z - a.clip.z) * t, a.clip.w + (b.clip.w - a.clip.w) * t};
  r.depth = a.depth + (b.depth - a.depth) * t;
  for (int k = 0; k < 3; ++k) r.bary[k] = a.bary[k] + (b.bary[k] - a.bary[k]) * t;
  return r;
}

// Sutherland-Hodgman against the plane w = w_min (clip space): a triangle becomes 0, 3 or 4 vertices.
int clip_near(const ClipVertex in[3], float w_min, ClipVertex out[4]) {
  int n = 0;
  for (int i = 0; i < 3; ++i) {
    const ClipVertex& a = in[i];
    const ClipVertex& b = in[(i + 1) % 3];
    const float da = a.clip.w - w_min, db = b.clip.w - w_min;
    if (da >= 0) out[n++] = a;
    if ((da >= 0) != (db >= 0)) out[n++] = lerp_vertex(a, b, da / (da - db));
  }
  return n;
}

// Edge function of the edge a->b at p: > 0 on the inside of a counter-clockwise (on screen,
// y down, positive area) triangle.
inline double edge(double ax, double ay, double bx, double by, double px, double py) {
  return (bx - ax) * (py - ay) - (by - ay) * (px - ax);
}

// Top edges are horizontal with the triangle below; left edges go up the screen (dy < 0).
inline bool is_top_left(double ax, double ay, double bx, double by) {
  const double dx = bx - ax, dy = by - ay;
  return (dy == 0 && dx > 0) || dy < 0;
}

int clamp_to_int(double v, int lo, int hi) {
  if (!(v > lo)) return lo;  // also NaN
  if (v > hi) return hi;
  return static_cast<int>(v);
}

void emit_triangle(const ClipVertex* v0, const ClipVertex* v1, const ClipVertex* v2, uint32_t triangle,
                   const RasterInput& input, std::vector<ScreenTriangle>& out) {
  const ClipVertex* v[3] = {v0, v1, v2};
  ScreenTriangle t;
  // Clip space -> NDC -> pixel coordinates (x right, y down).
  for (int k = 0; k < 3; ++k) {
    const double inv_w = 1.0 / static_cast<double>(v[k]->clip.w);
    t.x[k] = (static_cast<double>(v[k]->clip.x) * inv_w + 1.0) * 0.5 * input.width;
    t.y[k] = (1.0 - static_cast<double>(v[k]->clip.y) * inv_w) * 0.5 * input.height;
    t.inv_w[k] = static_cast<float>(inv_w);
    t.depth[k] = v[k]->depth;
    for (int j = 0; j < 3; ++j) t.bary[k][j] = v[k]->bary[j];
  }
  const double area2 = edge(t.x[0], t.y[0], t.x[1], t.y[1], t.x[2], t.y[2]);
  if (!(area2 != 0) || !std::isfinite(area2)) return;
  // Counter-clockwise in view space (y up) is clockwise in pixel coordinates (y down): area < 0.
  t.front_facing = area2 < 0;
  const bool cull = input.cull_back && (*input.cull_back)[triangle];
  if (cull && !t.front_facing) return;
  if (area2 < 0) {  // reorder to a positive area so "inside" is E >= 0 for every edge
    std::swap(t.x[1], t.x[2]);
    std::swap(t.y[1], t.y[2]);
    std::swap(t.inv_w[1], t.inv_w[2]);
    std::swap(t.depth[1], t.depth[2]);
    for (int j = 0; j < 3; ++j) std::swap(t.bary[1][j], t.bary[2][j]);
  }
  t.inv_area = 1.0 / std::abs(area2);
  t.triangle = triangle;
  // Pixels whose centre j + 0.5 lies within [min x, max x].
  const double min_x = std::min({t.x[0], t.x[1], t.x[2]}), max_x = std::max({t.x[0], t.x[1], t.x[2]});
  const double min_y = std::min({t.y[0], t.y[1], t.y[2]}), max_y = std::max({t.y[0], t.y[1], t.y[2]});
  t.x0 = clamp_to_int(std::ceil(min_x - 0.5), 0, input.width - 1);
  t.x1 = clamp_to_int(std::floor(max_x - 0.5), -1, input.width - 1);
  t.y0 = clamp_to_int(std::ceil(min_y - 0.5), 0, input.height - 1);
  t.y1 = clamp_to_int(std::floor(max_y - 0.5), -1, input.height - 1);
  if (max_x - 0.5 < 0 || max_y - 0.5 < 0 || min_x - 0.5 > input.width - 1 || min_y - 0.5 > input.height - 1) return;
  if (t.x1 < t.x0 || t.y1 < t.y0) return;
  out.push_back(t);
}

void setup_range(const RasterInput& input, size_t begin, size_t end, std::vector<ScreenTriangle>& out) {
  const auto& clip = *input.clip;
  const auto& depth = *input.depth;
  const auto& idx = *input.indices;
  for (size_t tri = begin; tri < end; ++tri) {
    ClipVertex in[3];
    for (int k = 0; k < 3; ++k) {
      const uint32_t vi = idx[tri * 3 + k];
      in[k].clip = clip[vi];
      in[k].depth = depth[vi];
      for (int j = 0; j < 3; ++j) in[k].bary[j] = j == k ? 1.0f : 0.0f;
    }
    // Trivial rejection against the side planes (valid in homogeneous clip space for any w).
    auto all = [&](auto outside) { return outside(in[0].clip) && outside(in[1].clip) && outside(in[2].clip); };
    if (all([](const Vec4& c) { return c.x > c.w; }) || all([](const Vec4& c) { return c.x < -c.w; }) ||
        all([](const Vec4& c) { return c.y > c.w; }) || all([](const Vec4& c) { return c.y < -c.w; }))
      continue;
    ClipVertex poly[4];
    const int n = clip_near(in, input.w_min, poly);
    for (int k = 1; k + 1 < n; ++k) emit_triangle(&poly[0], &poly[k], &poly[k + 1], static_cast<uint32_t>(tri), input, out);
  }
}

}  // namespace

void ScreenTriangle::original_barycentrics(double px, double py, float out[3]) const {
  double lw[3];  // screen-space barycentric / w
  double sum = 0;
  for (int k = 0; k < 3; ++k) {
    const int a = (k + 1) % 3, b = (k + 2) % 3;
    lw[k] = edge(x[a], y[a], x[b], y[b], px, py) * inv_area * inv_w[k];
    sum += lw[k];
  }
  const double inv_sum = sum != 0 ? 1.0 / sum : 0.0;
  for (int j = 0; j < 3; ++j)
    out[j] = static_cast<float>((lw[0] * bary[0][j] + lw[1] * bary[1][j] + lw[2] * bary[2][j]) * inv_sum);
}

float ScreenTriangle::depth_at(double px, double py) const {
  double num = 0, den = 0;
  for (int k = 0; k < 3; ++k) {
    const int a = (k + 1) % 3, b = (k + 2) % 3;
    const double lw = edge(x[a], y[a], x[b], y[b], px, py) * inv_w[k];
    num += lw * depth[k];
    den += lw;
  }
  return static_cast<float>(num / den);
}

std::vector<ScreenTriangle> setup_triangles(const RasterInput& input) {
  CGSR_CHECK(input.clip && input.depth && input.indices, "raster input without geometry");
  CGSR_CHECK(input.width > 0 && input.height > 0, "raster target without pixels");
  const size_t count = input.indices->size() / 3;
  constexpr size_t kChunk = 2048;
  const size_t chunks = (count + kChunk - 1) / kChunk;
  std::vector<std::vector<ScreenTriangle>> parts(chunks);
  tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
    setup_range(input, c * kChunk, std::min(count, (c + 1) * kChunk), parts[c]);
  });
  std::vector<ScreenTriangle> out;
  size_t total = 0;
  for (const auto& p : parts) total += p.size();
  out.reserve(total);
  for (auto& p : parts) out.insert(out.end(), p.begin(), p.end());
  return out;
}

void rasterize(const RasterInput& input, const std::vector<ScreenTriangle>& triangles, VisibilityBuffer& out,
               const CoverageTest& coverage_test) {
  const int W = input.width, H = input.height, ts = input.tile_size;
  CGSR_CHECK(ts > 0, "tile size must be positive");
  out.width = W;
  out.height = H;
  out.depth.assign(static_cast<size_t>(W) * H, std::numeric_limits<float>::infinity());
  out.screen_index.assign(static_cast<size_t>(W) * H, -1);

  // Bin triangles into the tiles their pixel bounds touch (in order, so tiles stay deterministic).
  const int tiles_x = (W + ts - 1) / ts, tiles_y = (H + ts - 1) / ts;
  std::vector<std::vector<int32_t>> bins(static_cast<size_t>(tiles_x) * tiles_y);
  for (size_t i = 0; i < triangles.size(); ++i) {
    const auto& t = triangles[i];
    for (int ty = t.y0 / ts; ty <= t.y1 / ts; ++ty)
      for (int tx = t.x0 / ts; tx <= t.x1 / ts; ++tx) bins[static_cast<size_t>(ty) * tiles_x + tx].push_back(static_cast<int32_t>(i));
  }

  const auto* alpha = input.alpha_tested;
  tbb::parallel_for(size_t(0), bins.size(), [&](size_t tile) {
    const int tx = static_cast<int>(tile) % tiles_x, ty = static_cast<int>(tile) / tiles_x;
    const int tile_x0 = tx * ts, tile_y0 = ty * ts;
    const int tile_x1 = std::min(W - 1, tile_x0 + ts - 1), tile_y1 = std::min(H - 1, tile_y0 + ts - 1);
    for (const int32_t index : bins[tile]) {
      const ScreenTriangle& t = triangles[index];
      const bool test_alpha = alpha && (*alpha)[t.triangle] && coverage_test;
      bool top_left[3];
      for (int k = 0; k < 3; ++k) {
        const int a = (k + 1) % 3, b = (k + 2) % 3;
        top_left[k] = is_top_left(t.x[a], t.y[a], t.x[b], t.y[b]);
      }
      const int x0 = std::max(t.x0, tile_x0), x1 = std::min(t.x1, tile_x1);
      const int y0 = std::max(t.y0, tile_y0), y1 = std::min(t.y1, tile_y1);
      for (int py = y0; py <= y1; ++py) {
        const double cy = py + 0.5;
        for (int px = x0; px <= x1; ++px) {
          const double cx = px + 0.5;
          double e[3];
          bool inside = true;
          for (int k = 0; k < 3 && inside; ++k) {
            const int a = (k + 1) % 3, b = (k + 2) % 3;
            e[k] = edge(t.x[a], t.y[a], t.x[b], t.y[b], cx, cy);
            inside = e[k] > 0 || (e[k] == 0 && top_left[k]);
          }
          if (!inside) continue;
          // Perspective-correct depth attribute: sum(e_k / w_k * d_k) / sum(e_k / w_k).
          const double l0 = e[0] * t.inv_w[0], l1 = e[1] * t.inv_w[1], l2 = e[2] * t.inv_w[2];
          const float d = static_cast<float>((l0 * t.depth[0] + l1 * t.depth[1] + l2 * t.depth[2]) / (l0 + l1 + l2));
          const size_t p = static_cast<size_t>(py) * W + px;
          if (!(d < out.depth[p])) continue;
          if (test_alpha && !coverage_test(t, cx, cy)) continue;
          out.depth[p] = d;
          out.screen_index[p] = index;
        }
      }
    }
  });
}

}  // namespace cgsr
