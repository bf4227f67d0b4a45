#include "render_data/q3/surface_obstacles.h"

#include <algorithm>
#include <cmath>

namespace cgsr::q3 {

// Region tests on the barycentric coordinates: the nearest point is a vertex, a point on an edge,
// or inside the face.
Vec3 closest_point_on_triangle(Vec3 p, Vec3 a, Vec3 b, Vec3 c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const float d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const float d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Vec3 cp = p - c;
  const float d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const float denom = va + vb + vc;
  if (!(std::fabs(denom) > 0)) return a;  // degenerate (zero-area) triangle
  const float v = vb / denom, w = vc / denom;
  return a + ab * v + ac * w;
}

int64_t SurfaceObstacles::key(int x, int y, int z) const {
  return (static_cast<int64_t>(x & 0x1FFFFF) << 42) | (static_cast<int64_t>(y & 0x1FFFFF) << 21) |
         static_cast<int64_t>(z & 0x1FFFFF);
}

SurfaceObstacles::SurfaceObstacles(std::vector<std::array<Vec3, 3>> triangles, float cell_size)
    : triangles_(std::move(triangles)), cell_(cell_size) {
  for (uint32_t t = 0; t < triangles_.size(); ++t) {
    const auto& tri = triangles_[t];
    const Vec3 lo = min(min(tri[0], tri[1]), tri[2]), hi = max(max(tri[0], tri[1]), tri[2]);
    const int x0 = static_cast<int>(std::floor(lo.x / cell_)), x1 = static_cast<int>(std::floor(hi.x / cell_));
    const int y0 = static_cast<int>(std::floor(lo.y / cell_)), y1 = static_cast<int>(std::floor(hi.y / cell_));
    const int z0 = static_cast<int>(std::floor(lo.z / cell_)), z1 = static_cast<int>(std::floor(hi.z / cell_));
    for (int x = x0; x <= x1; ++x)
      for (int y = y0; y <= y1; ++y)
        for (int z = z0; z <= z1; ++z) cells_[key(x, y, z)].push_back(t);
  }
}

float SurfaceObstacles::distance(Vec3 p, float limit) const {
  float best = limit;
  const int x0 = static_cast<int>(std::floor((p.x - limit) / cell_)), x1 = static_cast<int>(std::floor((p.x + limit) / cell_));
  const int y0 = static_cast<int>(std::floor((p.y - limit) / cell_)), y1 = static_cast<int>(std::floor((p.y + limit) / cell_));
  const int z0 = static_cast<int>(std::floor((p.z - limit) / cell_)), z1 = static_cast<int>(std::floor((p.z + limit) / cell_));
  for (int x = x0; x <= x1; ++x)
    for (int y = y0; y <= y1; ++y)
      for (int z = z0; z <= z1; ++z) {
        const auto it = cells_.find(key(x, y, z));
        if (it == cells_.end()) continue;
        for (uint32_t t : it->second) {
          const auto& tri = triangles_[t];
          best = std::min(best, length(p - closest_point_on_triangle(p, tri[0], tri[1], tri[2])));
        }
      }
  return best;
}

bool SurfaceObstacles::segment_clear(Vec3 a, Vec3 b, float clearance) const {
  const float len = length(b - a);
  const int steps = std::max(1, static_cast<int>(std::ceil(len / (0.5f * clearance))));
  for (int i = 0; i <= steps; ++i)
    if (distance(lerp(a, b, static_cast<float>(i) / steps), clearance) < clearance) return false;
  return true;
}

}  // namespace cgsr::q3
