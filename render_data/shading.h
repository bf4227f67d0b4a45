#pragma once
// The one interface between the raster pipeline and shading: the pipeline reconstructs a
// SurfacePoint (world space) for every visible pixel and asks a SurfaceShader for its linear
// RGB colour. Fog, sky and the sRGB encoding are the pipeline's business, not the shader's.

#include <memory>
#include <vector>

#include "render_data/scene.h"
#include "render_data/shadow_maps.h"
#include "render_data/texture_sampler.h"

namespace cgsr {

struct SurfacePoint {
  Vec3 position;          // world space
  Vec3 normal;            // world space, unit, facing the viewer
  Vec3 to_eye;            // world space, unit, from the point towards the camera
  Vec3 albedo;            // linear RGB: texture x tint x vertex colour
  Vec3 lightmap;          // linear RGB lightmap sample (only with a lightmap material)
  const Material* material = nullptr;
};

class SurfaceShader {
 public:
  virtual ~SurfaceShader() = default;
  virtual Vec3 shade(const SurfacePoint& point) const = 0;  // linear RGB, >= 0
};

// Lambert diffuse + Blinn-Phong specular from every scene light, point-light falloff
// intensity / (1 + (d / radius)^2), shadow-map visibility where a map exists, plus the scene's
// ambient term. Lightmapped materials: albedo x lightmap x lightmap_scale. Unlit: albedo.
class BlinnPhongShader : public SurfaceShader {
 public:
  // `shadow_maps` has one entry per scene light (empty maps for lights without shadows); it must
  // outlive the shader.
  BlinnPhongShader(const Scene& scene, const std::vector<ShadowMap>& shadow_maps);
  Vec3 shade(const SurfacePoint& point) const override;

 private:
  const Scene& scene_;
  const std::vector<ShadowMap>& shadow_maps_;
};

}  // namespace cgsr
