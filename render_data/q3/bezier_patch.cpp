#include "render_data/q3/bezier_patch.h"

#include "core/error.h"

namespace cgsr::q3 {
namespace {

// Quadratic Bernstein weights for the parameter pair (s, t) = (1 - t, t). Written so that
// swapping s and t swaps w0 and w2 and keeps w1 bit for bit.
struct Weights {
  float w0, w1, w2;
};
Weights bernstein(float s, float t) { return {s * s, 2.0f * (s * t), t * t}; }

// (a*w0 + c*w2) + b*w1: the same bits when (a, w0) and (c, w2) trade places.
template <class V>
V blend(const V& a, const V& b, const V& c, const Weights& w);

template <>
float blend(const float& a, const float& b, const float& c, const Weights& w) {
  return (a * w.w0 + c * w.w2) + b * w.w1;
}
template <>
Vec3 blend(const Vec3& a, const Vec3& b, const Vec3& c, const Weights& w) {
  return {blend(a.x, b.x, c.x, w), blend(a.y, b.y, c.y, w), blend(a.z, b.z, c.z, w)};
}
template <>
Vec2 blend(const Vec2& a, const Vec2& b, const Vec2& c, const Weights& w) {
  return {blend(a.x, b.x, c.x, w), blend(a.y, b.y, c.y, w)};
}
template <>
std::array<float, 4> blend(const std::array<float, 4>& a, const std::array<float, 4>& b,
                           const std::array<float, 4>& c, const Weights& w) {
  return {blend(a[0], b[0], c[0], w), blend(a[1], b[1], c[1], w), blend(a[2], b[2], c[2], w),
          blend(a[3], b[3], c[3], w)};
}

PatchVertex as_patch_vertex(const BspVertex& v) {
  PatchVertex p;
  p.position = v.position;
  p.normal = v.normal;
  p.uv = v.uv;
  p.lightmap_uv = v.lightmap_uv;
  for (int c = 0; c < 4; ++c) p.color[c] = v.color[c] / 255.0f;
  return p;
}

// Rows first (along u), then the three row results along v.
PatchVertex evaluate(const BspVertex* const rows[3], const Weights& wu, const Weights& wv) {
  PatchVertex r[3];
  for (int j = 0; j < 3; ++j) {
    const PatchVertex a = as_patch_vertex(rows[j][0]), b = as_patch_vertex(rows[j][1]), c = as_patch_vertex(rows[j][2]);
    r[j].position = blend(a.position, b.position, c.position, wu);
    r[j].normal = blend(a.normal, b.normal, c.normal, wu);
    r[j].uv = blend(a.uv, b.uv, c.uv, wu);
    r[j].lightmap_uv = blend(a.lightmap_uv, b.lightmap_uv, c.lightmap_uv, wu);
    r[j].color = blend(a.color, b.color, c.color, wu);
  }
  PatchVertex out;
  out.position = blend(r[0].position, r[1].position, r[2].position, wv);
  out.normal = normalize(blend(r[0].normal, r[1].normal, r[2].normal, wv));
  out.uv = blend(r[0].uv, r[1].uv, r[2].uv, wv);
  out.lightmap_uv = blend(r[0].lightmap_uv, r[1].lightmap_uv, r[2].lightmap_uv, wv);
  out.color = blend(r[0].color, r[1].color, r[2].color, wv);
  return out;
}

}  // namespace

PatchVertex evaluate_patch(const BspVertex* control3x3, float u, float v) {
  const BspVertex* rows[3] = {control3x3, control3x3 + 3, control3x3 + 6};
  return evaluate(rows, bernstein(1.0f - u, u), bernstein(1.0f - v, v));
}

TessellatedPatch tessellate_patch(const std::vector<BspVertex>& control, int width, int height, int level) {
  CGSR_CHECK(width >= 3 && height >= 3 && width % 2 == 1 && height % 2 == 1, "patch sides must be odd and >= 3");
  CGSR_CHECK(control.size() == static_cast<size_t>(width) * height, "patch control point count");
  CGSR_CHECK(level >= 1, "patch tessellation level must be >= 1");
  const int patches_x = (width - 1) / 2, patches_y = (height - 1) / 2;
  TessellatedPatch out;
  out.columns = patches_x * level + 1;
  out.rows = patches_y * level + 1;
  out.vertices.reserve(static_cast<size_t>(out.columns) * out.rows);

  // Weights of local step k in [0, level]: t = k/level and s = (level-k)/level, each rounded once.
  std::vector<Weights> weights(level + 1);
  for (int k = 0; k <= level; ++k)
    weights[k] = bernstein(static_cast<float>(level - k) / level, static_cast<float>(k) / level);

  for (int row = 0; row < out.rows; ++row) {
    const int py = std::min(row / level, patches_y - 1), ky = row - py * level;
    for (int col = 0; col < out.columns; ++col) {
      const int px = std::min(col / level, patches_x - 1), kx = col - px * level;
      const BspVertex* rows[3];
      for (int j = 0; j < 3; ++j) rows[j] = &control[static_cast<size_t>(2 * py + j) * width + 2 * px];
      out.vertices.push_back(evaluate(rows, weights[kx], weights[ky]));
    }
  }

  // Winding: the BSP's polygons are clockwise seen from their front (the geometric normal
  // cross(b-a, c-a) opposes the surface normal); the patch follows, decided once per grid so a
  // few degenerate quads cannot flip parts of it.
  double agreement = 0;
  const auto& v = out.vertices;
  for (int row = 0; row + 1 < out.rows; ++row)
    for (int col = 0; col + 1 < out.columns; ++col) {
      const size_t a = static_cast<size_t>(row) * out.columns + col, b = a + 1, d = a + out.columns;
      const Vec3 geometric = cross(v[b].position - v[a].position, v[d].position - v[a].position);
      agreement += dot(geometric, v[a].normal + v[b].normal + v[d].normal);
    }
  const bool flip = agreement > 0;
  out.indices.reserve(static_cast<size_t>(out.rows - 1) * (out.columns - 1) * 6);
  for (int row = 0; row + 1 < out.rows; ++row)
    for (int col = 0; col + 1 < out.columns; ++col) {
      const uint32_t a = static_cast<uint32_t>(row * out.columns + col), b = a + 1,
                     d = a + static_cast<uint32_t>(out.columns), e = d + 1;
      if (!flip) {
        out.indices.insert(out.indices.end(), {a, b, d, b, e, d});
      } else {
        out.indices.insert(out.indices.end(), {a, d, b, b, d, e});
      }
    }
  return out;
}

}  // namespace cgsr::q3
