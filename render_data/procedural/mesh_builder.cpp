#include "render_data/procedural/mesh_builder.h"

#include <cmath>

#include "render_data/vec_math.h"

namespace cgsr {

void perpendicular_basis(Vec3 axis, Vec3& u, Vec3& v) {
  const Vec3 helper = std::abs(axis.y) < 0.9f ? Vec3{0, 1, 0} : Vec3{1, 0, 0};
  u = normalize(cross(helper, axis));
  v = cross(axis, u);
}

MeshBuilder::MeshBuilder(std::string name, int material, int object_id) {
  mesh_.name = std::move(name);
  mesh_.material = material;
  mesh_.object_id = object_id;
}

uint32_t MeshBuilder::vertex(Vec3 p, Vec3 n, Vec2 uv) {
  mesh_.positions.push_back(p);
  mesh_.normals.push_back(n);
  mesh_.uvs.push_back(uv);
  return static_cast<uint32_t>(mesh_.positions.size() - 1);
}

void MeshBuilder::triangle(uint32_t a, uint32_t b, uint32_t c) {
  mesh_.indices.push_back(a);
  mesh_.indices.push_back(b);
  mesh_.indices.push_back(c);
}

void MeshBuilder::quad(Vec3 origin, Vec3 u, Vec3 v, float uv_per_metre) {
  const Vec3 n = normalize(cross(u, v));
  const float su = length(u) * uv_per_metre, sv = length(v) * uv_per_metre;
  // Texture v runs against the quad's v axis so that "up" on a wall is up in the texture.
  const uint32_t a = vertex(origin, n, {0, sv}), b = vertex(origin + u, n, {su, sv});
  const uint32_t c = vertex(origin + u + v, n, {su, 0}), d = vertex(origin + v, n, {0, 0});
  triangle(a, b, c);
  triangle(a, c, d);
}

void MeshBuilder::box(Vec3 lo, Vec3 hi, float uv_per_metre, bool inward) {
  const Vec3 c = (lo + hi) * 0.5f, h = (hi - lo) * 0.5f;
  if (!inward) {
    oriented_box(c, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, h, uv_per_metre);
    return;
  }
  // Faces pointing into the box (cross(u, v) is the normal; side faces keep v = up).
  const Vec3 ex{hi.x - lo.x, 0, 0}, ey{0, hi.y - lo.y, 0}, ez{0, 0, hi.z - lo.z};
  quad(lo + ez, -ez, ey, uv_per_metre);            // -x wall, normal +x
  quad({hi.x, lo.y, lo.z}, ez, ey, uv_per_metre);  // +x wall, normal -x
  quad(lo, ez, ex, uv_per_metre);                  // floor, normal +y
  quad({lo.x, hi.y, lo.z}, ex, ez, uv_per_metre);  // ceiling, normal -y
  quad(lo, ex, ey, uv_per_metre);                  // -z wall, normal +z
  quad({hi.x, lo.y, hi.z}, -ex, ey, uv_per_metre); // +z wall, normal -z
}

void MeshBuilder::oriented_box(Vec3 c, Vec3 ax, Vec3 ay, Vec3 az, Vec3 h, float uv_per_metre) {
  const Vec3 X = ax * h.x, Y = ay * h.y, Z = az * h.z;
  // Each face: a corner and two edges with cross(u, v) pointing outwards (X x Y = Z, ...).
  quad(c + X - Y + Z, -Z * 2, Y * 2, uv_per_metre);  // +x
  quad(c - X - Y - Z, Z * 2, Y * 2, uv_per_metre);   // -x
  quad(c - X + Y - Z, Z * 2, X * 2, uv_per_metre);   // +y
  quad(c - X - Y - Z, X * 2, Z * 2, uv_per_metre);   // -y
  quad(c - X - Y + Z, X * 2, Y * 2, uv_per_metre);   // +z
  quad(c + X - Y - Z, -X * 2, Y * 2, uv_per_metre);  // -z
}

void MeshBuilder::cylinder(Vec3 base, Vec3 axis, float radius, int segments, float uv_per_metre, bool caps) {
  const float len = length(axis);
  const Vec3 a = axis / len;
  Vec3 u, v;
  perpendicular_basis(a, u, v);
  const float circumference = kTwoPiF * radius * uv_per_metre;
  const uint32_t first = static_cast<uint32_t>(mesh_.positions.size());
  for (int s = 0; s <= segments; ++s) {
    const float t = kTwoPiF * s / segments;
    const Vec3 n = u * std::cos(t) + v * std::sin(t);
    vertex(base + n * radius, n, {circumference * s / segments, len * uv_per_metre});
    vertex(base + axis + n * radius, n, {circumference * s / segments, 0});
  }
  for (int s = 0; s < segments; ++s) {
    const uint32_t b0 = first + 2 * s, t0 = b0 + 1, b1 = b0 + 2, t1 = b0 + 3;
    triangle(b0, b1, t1);
    triangle(b0, t1, t0);
  }
  if (!caps) return;
  for (int end = 0; end < 2; ++end) {
    const Vec3 centre = end ? base + axis : base;
    const Vec3 n = end ? a : -a;
    const uint32_t c = vertex(centre, n, {0.5f, 0.5f});
    const uint32_t ring = static_cast<uint32_t>(mesh_.positions.size());
    for (int s = 0; s < segments; ++s) {
      const float t = kTwoPiF * s / segments;
      const Vec3 d = u * std::cos(t) + v * std::sin(t);
      vertex(centre + d * radius, n, {0.5f + 0.5f * std::cos(t), 0.5f + 0.5f * std::sin(t)});
    }
    for (int s = 0; s < segments; ++s) {
      const uint32_t p = ring + s, q = ring + (s + 1) % segments;
      if (end) triangle(c, p, q);
      else triangle(c, q, p);
    }
  }
}

void MeshBuilder::sphere(Vec3 centre, float radius, int rings, int segments, float uv_repeats) {
  const uint32_t first = static_cast<uint32_t>(mesh_.positions.size());
  for (int r = 0; r <= rings; ++r) {
    const float phi = kPiF * r / rings;  // 0 at the top
    for (int s = 0; s <= segments; ++s) {
      const float theta = kTwoPiF * s / segments;
      const Vec3 n{std::sin(phi) * std::cos(theta), std::cos(phi), -std::sin(phi) * std::sin(theta)};
      vertex(centre + n * radius, n, {uv_repeats * 2 * s / segments, uv_repeats * static_cast<float>(r) / rings});
    }
  }
  const int stride = segments + 1;
  for (int r = 0; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const uint32_t a = first + r * stride + s, b = a + 1, c = a + stride, d = c + 1;
      if (r > 0) triangle(a, c, b);
      if (r < rings - 1) triangle(b, c, d);
    }
}

void MeshBuilder::torus(Vec3 centre, Vec3 axis, float major, float minor, int major_segments, int minor_segments,
                        float uv_repeats) {
  const Vec3 a = normalize(axis);
  Vec3 u, v;
  perpendicular_basis(a, u, v);
  const uint32_t first = static_cast<uint32_t>(mesh_.positions.size());
  for (int i = 0; i <= major_segments; ++i) {
    const float t = kTwoPiF * i / major_segments;
    const Vec3 radial = u * std::cos(t) + v * std::sin(t);
    for (int j = 0; j <= minor_segments; ++j) {
      const float p = kTwoPiF * j / minor_segments;
      const Vec3 n = radial * std::cos(p) + a * std::sin(p);
      vertex(centre + radial * major + n * minor, n,
             {uv_repeats * 4 * i / major_segments, uv_repeats * static_cast<float>(j) / minor_segments});
    }
  }
  const int stride = minor_segments + 1;
  for (int i = 0; i < major_segments; ++i)
    for (int j = 0; j < minor_segments; ++j) {
      const uint32_t a0 = first + i * stride + j, a1 = a0 + 1, b0 = a0 + stride, b1 = b0 + 1;
      triangle(a0, b0, b1);
      triangle(a0, b1, a1);
    }
}

void MeshBuilder::tube(const std::vector<Vec3>& path, float radius, int segments, float uv_per_metre) {
  if (path.size() < 2) return;
  const uint32_t first = static_cast<uint32_t>(mesh_.positions.size());
  float along = 0;
  Vec3 u, v;
  perpendicular_basis(normalize(path[1] - path[0]), u, v);
  for (size_t k = 0; k < path.size(); ++k) {
    if (k > 0) along += length(path[k] - path[k - 1]);
    const Vec3 dir = normalize(k + 1 < path.size() ? path[k + 1] - path[k] : path[k] - path[k - 1]);
    // Parallel transport of the ring frame keeps the tube from twisting.
    u = normalize(u - dir * dot(u, dir));
    v = cross(dir, u);
    for (int s = 0; s <= segments; ++s) {
      const float t = kTwoPiF * s / segments;
      const Vec3 n = u * std::cos(t) + v * std::sin(t);
      vertex(path[k] + n * radius, n, {static_cast<float>(s) / segments, along * uv_per_metre});
    }
  }
  const int stride = segments + 1;
  for (size_t k = 0; k + 1 < path.size(); ++k)
    for (int s = 0; s < segments; ++s) {
      const uint32_t a = first + static_cast<uint32_t>(k) * stride + s, b = a + 1, c = a + stride, d = c + 1;
      triangle(a, b, d);
      triangle(a, d, c);
    }
}

Mesh MeshBuilder::finish() { return std::move(mesh_); }

}  // namespace cgsr
