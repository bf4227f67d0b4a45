#include "render_data/shading.h"

#include <algorithm>
#include <cmath>

namespace cgsr {

BlinnPhongShader::BlinnPhongShader(const Scene& scene, const std::vector<ShadowMap>& shadow_maps)
    : scene_(scene), shadow_maps_(shadow_maps) {}

Vec3 BlinnPhongShader::shade(const SurfacePoint& s) const {
  const Material& mat = *s.material;
  if (mat.unlit) return s.albedo;
  if (mat.lightmap_texture >= 0) return s.albedo * s.lightmap * mat.lightmap_scale;

  Vec3 diffuse = scene_.ambient, specular{};
  for (size_t i = 0; i < scene_.lights.size(); ++i) {
    const Light& light = scene_.lights[i];
    Vec3 to_light;
    float strength = light.intensity;
    if (light.type == LightType::Directional) {
      to_light = -normalize(light.direction);
    } else {
      const Vec3 d = light.position - s.position;
      const float dist = length(d);
      if (!(dist > 0)) continue;
      to_light = d / dist;
      const float q = dist / light.radius;
      strength /= 1.0f + q * q;
    }
    const float n_dot_l = dot(s.normal, to_light);
    if (n_dot_l <= 0 || strength <= 0) continue;
    const float visible = i < shadow_maps_.size() ? shadow_maps_[i].visibility(s.position, s.normal) : 1.0f;
    if (visible <= 0) continue;
    const Vec3 radiance = light.color * (strength * visible);
    diffuse += radiance * n_dot_l;
    if (mat.specular > 0) {
      const Vec3 h = normalize(to_light + s.to_eye);
      specular += radiance * (mat.specular * std::pow(std::max(0.0f, dot(s.normal, h)), mat.shininess));
    }
  }
  return s.albedo * diffuse + specular;
}

}  // namespace cgsr
