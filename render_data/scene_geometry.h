#pragma once
// A scene flattened for rasterization: every mesh's vertices and triangles in shared world-space
// arrays, per-triangle material/object lookups, and texture mip chains. Built once per scene and
// shared read-only by every view (camera frames at every resolution, shadow maps).

#include <cstdint>
#include <vector>

#include "render_data/raster_core.h"
#include "render_data/scene.h"
#include "render_data/texture_sampler.h"

namespace cgsr {

class SceneGeometry {
 public:
  explicit SceneGeometry(const Scene& scene);  // validates the scene first

  const Scene& scene() const { return scene_; }
  size_t vertex_count() const { return positions.size(); }
  size_t triangle_count() const { return indices.size() / 3; }
  const Mesh& mesh_of(uint32_t triangle) const { return scene_.meshes[triangle_mesh[triangle]]; }
  const Material& material_of(uint32_t triangle) const { return scene_.materials[mesh_of(triangle).material]; }
  const MipChain* texture(int index) const { return index >= 0 ? &textures[index] : nullptr; }

  // Alpha test of an alpha-tested triangle at pixel coordinates (px, py) of the view that
  // produced `tri`: samples the albedo alpha with the pixel's uv footprint (trilinear).
  bool alpha_covers(const ScreenTriangle& tri, double px, double py) const;

  // World-space attributes (indexed by vertex) and triangles.
  std::vector<Vec3> positions, normals, colors;  // colors: white where a mesh has none
  std::vector<Vec2> uvs, lightmap_uvs;           // lightmap_uvs: zero where a mesh has none
  std::vector<uint32_t> indices;
  std::vector<int32_t> triangle_mesh;               // mesh index per triangle
  std::vector<uint8_t> cull_back, alpha_tested;     // per triangle flags for the raster stage
  std::vector<MipChain> textures;                   // one per Scene::textures entry

 private:
  Scene scene_;
};

// uv at (px, py) and its screen-space derivatives (one pixel right, one pixel down).
struct UvFootprint {
  Vec2 uv, duv_dx, duv_dy;
};
UvFootprint uv_footprint(const SceneGeometry& geometry, const ScreenTriangle& tri, double px, double py);

}  // namespace cgsr
