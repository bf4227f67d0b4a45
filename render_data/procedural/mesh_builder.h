#pragma once
// Builds meshes from primitives (quads, boxes, cylinders, spheres, tori, tubes along a path).
// Texture coordinates are world-scaled (`uv_per_metre` texture repeats per metre) so texel
// density is the same on every surface; front faces point outwards (counter-clockwise seen
// from outside).

#include <string>
#include <vector>

#include "render_data/scene.h"

namespace cgsr {

class MeshBuilder {
 public:
  MeshBuilder(std::string name, int material, int object_id);

  // A rectangle origin + a * u + b * v for a, b in [0,1]; its normal is normalize(cross(u, v)).
  void quad(Vec3 origin, Vec3 u, Vec3 v, float uv_per_metre);
  // Axis-aligned box [lo, hi]; `inward` flips it (a room seen from inside).
  void box(Vec3 lo, Vec3 hi, float uv_per_metre, bool inward = false);
  // A box with its own orthonormal frame: centre, half extents along the frame axes.
  void oriented_box(Vec3 centre, Vec3 axis_x, Vec3 axis_y, Vec3 axis_z, Vec3 half, float uv_per_metre);
  // Cylinder from `base` along `axis` (its full length) with smooth side normals and flat caps.
  void cylinder(Vec3 base, Vec3 axis, float radius, int segments, float uv_per_metre, bool caps = true);
  void sphere(Vec3 centre, float radius, int rings, int segments, float uv_repeats);
  // Torus around `axis` through `centre`: ring radius `major`, tube radius `minor`.
  void torus(Vec3 centre, Vec3 axis, float major, float minor, int major_segments, int minor_segments,
             float uv_repeats);
  // A thin tube following a polyline (wires, cables): smooth normals, open ends.
  void tube(const std::vector<Vec3>& path, float radius, int segments, float uv_per_metre);

  bool empty() const { return mesh_.indices.empty(); }
  Mesh finish();

 private:
  uint32_t vertex(Vec3 p, Vec3 n, Vec2 uv);
  void triangle(uint32_t a, uint32_t b, uint32_t c);
  Mesh mesh_;
};

// Orthonormal vectors perpendicular to the unit vector `axis`.
void perpendicular_basis(Vec3 axis, Vec3& u, Vec3& v);

}  // namespace cgsr
