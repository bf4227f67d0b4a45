#pragma once
// The drawn surfaces of a level as obstacles for the camera. Brushes (bsp_trace.h) are what the
// game collides with, but curved patches and models are drawn without brushes of their own; a
// camera that only respects brushes could fly through a pillar. This keeps the camera a given
// distance from every drawn triangle. Quake space. Triangles are binned in a uniform grid.

#include <array>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "render_data/vec_math.h"

namespace cgsr::q3 {

class SurfaceObstacles {
 public:
  explicit SurfaceObstacles(std::vector<std::array<Vec3, 3>> triangles, float cell_size = 64.0f);

  // Distance from `point` to the nearest triangle, or `limit` when none is closer than that.
  float distance(Vec3 point, float limit) const;
  // Whether every point of the segment stays at least 3/4 * `clearance` from every triangle:
  // points spaced clearance/2 apart are each checked for `clearance`.
  bool segment_clear(Vec3 a, Vec3 b, float clearance) const;

  size_t size() const { return triangles_.size(); }

 private:
  int64_t key(int x, int y, int z) const;
  std::vector<std::array<Vec3, 3>> triangles_;
  float cell_;
  std::unordered_map<int64_t, std::vector<uint32_t>> cells_;
};

// The closest point of triangle (a, b, c) to p.
Vec3 closest_point_on_triangle(Vec3 p, Vec3 a, Vec3 b, Vec3 c);

}  // namespace cgsr::q3
