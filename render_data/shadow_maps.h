#pragma once
// Shadow maps for lights with Light::shadows: an orthographic depth map covering the scene for
// directional lights, a six-face cube of 90-degree perspective depth maps for point lights.
// Geometry and lights are static, so a scene's shadow maps are rendered once and shared by
// every frame and resolution.

#include <vector>

#include "render_data/camera.h"
#include "render_data/raster_core.h"
#include "render_data/scene_geometry.h"

namespace cgsr {

struct ShadowSettings {
  int map_size = 1024;          // texels per side (per cube face for point lights)
  float normal_offset = 1.5f;   // lookup offset along the surface normal, in shadow-map texels
  float depth_bias = 0.002f;    // relative depth bias
  int pcf_radius = 1;           // (2r+1)^2 comparisons per lookup
};

class ShadowMap {
 public:
  ShadowMap() = default;
  ShadowMap(const SceneGeometry& geometry, const Light& light, const ShadowSettings& settings);

  bool empty() const { return faces_.empty(); }
  // Fraction of the light reaching world point `p` with unit normal `n` (1 = fully lit).
  float visibility(Vec3 p, Vec3 n) const;

 private:
  struct Face {
    FrameCamera camera;  // perspective faces (point lights)
    Mat4 view_projection;
    std::vector<float> depth;  // depth attribute of the nearest occluder per texel; +inf = none
  };
  float lookup(const Face& face, Vec3 p, float texel_world) const;

  LightType type_ = LightType::Point;
  Vec3 light_position_;
  Vec3 light_direction_;
  float ortho_radius_ = 0;  // directional: half extent of the orthographic view
  Vec3 ortho_center_;
  ShadowSettings settings_;
  std::vector<Face> faces_;
};

}  // namespace cgsr
