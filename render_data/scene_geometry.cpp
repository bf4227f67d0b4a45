#include "render_data/scene_geometry.h"

#include <oneapi/tbb/parallel_for.h>

namespace cgsr {

SceneGeometry::SceneGeometry(const Scene& scene) : scene_(scene) {
  validate_scene(scene_);
  size_t vertices = 0, triangles = 0;
  for (const auto& mesh : scene_.meshes) {
    vertices += mesh.positions.size();
    triangles += mesh.indices.size() / 3;
  }
  positions.reserve(vertices);
  normals.reserve(vertices);
  colors.reserve(vertices);
  uvs.reserve(vertices);
  lightmap_uvs.reserve(vertices);
  indices.reserve(triangles * 3);
  for (size_t m = 0; m < scene_.meshes.size(); ++m) {
    const Mesh& mesh = scene_.meshes[m];
    const Material& mat = scene_.materials[mesh.material];
    const uint32_t base = static_cast<uint32_t>(positions.size());
    for (size_t v = 0; v < mesh.positions.size(); ++v) {
      positions.push_back(mesh.positions[v]);
      normals.push_back(normalize(mesh.normals[v]));
      colors.push_back(mesh.colors.empty() ? Vec3{1, 1, 1} : mesh.colors[v]);
      uvs.push_back(mesh.uvs[v]);
      lightmap_uvs.push_back(mesh.lightmap_uvs.empty() ? Vec2{} : mesh.lightmap_uvs[v]);
    }
    for (uint32_t i : mesh.indices) indices.push_back(base + i);
    const bool alpha = mat.alpha_cutoff > 0 && mat.albedo_texture >= 0;
    for (size_t t = 0; t < mesh.indices.size() / 3; ++t) {
      triangle_mesh.push_back(static_cast<int32_t>(m));
      cull_back.push_back(mat.two_sided ? 0 : 1);
      alpha_tested.push_back(alpha ? 1 : 0);
    }
  }
  textures.resize(scene_.textures.size());
  tbb::parallel_for(size_t(0), scene_.textures.size(), [&](size_t t) { textures[t] = MipChain(scene_.textures[t]); });
}

UvFootprint uv_footprint(const SceneGeometry& g, const ScreenTriangle& tri, double px, double py) {
  const uint32_t* idx = &g.indices[static_cast<size_t>(tri.triangle) * 3];
  const Vec2 t0 = g.uvs[idx[0]], t1 = g.uvs[idx[1]], t2 = g.uvs[idx[2]];
  auto uv_at = [&](double x, double y) {
    float b[3];
    tri.original_barycentrics(x, y, b);
    return Vec2{t0.x * b[0] + t1.x * b[1] + t2.x * b[2], t0.y * b[0] + t1.y * b[1] + t2.y * b[2]};
  };
  UvFootprint f;
  f.uv = uv_at(px, py);
  f.duv_dx = uv_at(px + 1, py) - f.uv;
  f.duv_dy = uv_at(px, py + 1) - f.uv;
  return f;
}

bool SceneGeometry::alpha_covers(const ScreenTriangle& tri, double px, double py) const {
  const Material& mat = material_of(tri.triangle);
  const UvFootprint f = uv_footprint(*this, tri, px, py);
  return textures[mat.albedo_texture].sample_trilinear(f.uv, f.duv_dx, f.duv_dy).a >= mat.alpha_cutoff;
}

}  // namespace cgsr
