#include "render_data/shadow_maps.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace cgsr {
namespace {

// Depth-only render of the scene geometry with `view_projection`; the depth attribute per vertex
// is given by `depth_of` (view depth for perspective faces, distance along the light otherwise).
template <class DepthOf>
std::vector<float> render_depth(const SceneGeometry& g, const Mat4& view_projection, DepthOf depth_of, int size,
                                float w_min) {
  std::vector<Vec4> clip(g.vertex_count());
  std::vector<float> depth(g.vertex_count());
  for (size_t v = 0; v < clip.size(); ++v) {
    const Vec3 p = g.positions[v];
    clip[v] = view_projection * Vec4{p.x, p.y, p.z, 1};
    depth[v] = depth_of(p, clip[v]);
  }
  // Both faces of every triangle cast shadows, so closed and open geometry behave alike.
  const std::vector<uint8_t> no_culling(g.triangle_count(), 0);
  RasterInput in;
  in.clip = &clip;
  in.depth = &depth;
  in.indices = &g.indices;
  in.cull_back = &no_culling;
  in.alpha_tested = &g.alpha_tested;
  in.w_min = w_min;
  in.width = in.height = size;
  in.tile_size = 64;
  VisibilityBuffer vis;
  rasterize(in, setup_triangles(in), vis,
            [&g](const ScreenTriangle& t, double x, double y) { return g.alpha_covers(t, x, y); });
  return std::move(vis.depth);
}

}  // namespace

ShadowMap::ShadowMap(const SceneGeometry& g, const Light& light, const ShadowSettings& settings)
    : type_(light.type), light_position_(light.position), light_direction_(normalize(light.direction)),
      settings_(settings) {
  const int n = settings.map_size;
  if (light.type == LightType::Point) {
    // Cube faces +x, -x, +y, -y, +z, -z as 90-degree cameras (yaw/pitch of scene.h).
    const float yaw[6] = {-90, 90, 0, 0, 180, 0}, pitch[6] = {0, 0, 90, -90, 0, 0};
    for (int f = 0; f < 6; ++f) {
      CameraPose pose;
      pose.position = light.position;
      pose.yaw = yaw[f];
      pose.pitch = pitch[f];
      pose.vfov = 90;
      Face face;
      face.camera = make_frame_camera(pose, n, n, 0.02f, 1000.0f);
      face.view_projection = face.camera.view_projection;
      face.depth = render_depth(g, face.view_projection, [](Vec3, Vec4 c) { return c.w; }, n, 0.02f);
      faces_.push_back(std::move(face));
    }
    return;
  }
  // Directional: an orthographic view along the light direction covering the scene's bounds.
  Vec3 lo, hi;
  scene_bounds(g.scene(), lo, hi);
  if (!(lo.x <= hi.x)) return;  // no geometry, nothing casts shadows
  ortho_center_ = (lo + hi) * 0.5f;
  ortho_radius_ = std::max(1e-3f, length(hi - lo) * 0.5f);
  const Vec3 d = light_direction_;
  const Vec3 helper = std::abs(d.y) < 0.99f ? Vec3{0, 1, 0} : Vec3{1, 0, 0};
  const Vec3 right = normalize(cross(d, helper)), up = cross(right, d);
  // Light space: x = right / r, y = up / r (NDC), w = 1; depth = distance along d from the
  // plane one radius before the centre.
  Mat4 vp;
  const Vec3 rows[2] = {right / ortho_radius_, up / ortho_radius_};
  for (int r = 0; r < 2; ++r) {
    vp.m[0][r] = rows[r].x;
    vp.m[1][r] = rows[r].y;
    vp.m[2][r] = rows[r].z;
    vp.m[3][r] = -dot(rows[r], ortho_center_);
  }
  vp.m[0][2] = vp.m[1][2] = vp.m[2][2] = vp.m[3][2] = 0;
  vp.m[0][3] = vp.m[1][3] = vp.m[2][3] = 0;
  vp.m[3][3] = 1;
  Face face;
  face.view_projection = vp;
  const Vec3 origin = ortho_center_ - d * ortho_radius_;
  face.depth = render_depth(g, vp, [origin, d](Vec3 p, Vec4) { return dot(p - origin, d); }, n, 1e-6f);
  faces_.push_back(std::move(face));
}

float ShadowMap::lookup(const Face& face, Vec3 p, float texel_world) const {
  const int n = settings_.map_size;
  const Vec4 c = face.view_projection * Vec4{p.x, p.y, p.z, 1};
  if (!(c.w > 0)) return 1.0f;
  const float x = (c.x / c.w + 1.0f) * 0.5f * n - 0.5f, y = (1.0f - c.y / c.w) * 0.5f * n - 0.5f;
  const float depth = type_ == LightType::Point ? c.w : dot(p - (ortho_center_ - light_direction_ * ortho_radius_), light_direction_);
  const float bias = settings_.depth_bias * depth + texel_world;
  const int cx = static_cast<int>(std::lround(x)), cy = static_cast<int>(std::lround(y));
  const int r = settings_.pcf_radius;
  int lit = 0, total = 0;
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx) {
      const int tx = cx + dx, ty = cy + dy;
      ++total;
      if (tx < 0 || ty < 0 || tx >= n || ty >= n) {
        ++lit;  // outside the map: nothing recorded, lit
        continue;
      }
      if (depth - bias <= face.depth[static_cast<size_t>(ty) * n + tx]) ++lit;
    }
  return static_cast<float>(lit) / static_cast<float>(total);
}

float ShadowMap::visibility(Vec3 p, Vec3 n) const {
  if (faces_.empty()) return 1.0f;
  const int size = settings_.map_size;
  if (type_ == LightType::Directional) {
    const float texel = 2.0f * ortho_radius_ / size;
    return lookup(faces_[0], p + n * (settings_.normal_offset * texel), texel);
  }
  const Vec3 d = p - light_position_;
  const float ax = std::abs(d.x), ay = std::abs(d.y), az = std::abs(d.z);
  int f;
  if (ax >= ay && ax >= az) f = d.x > 0 ? 0 : 1;
  else if (ay >= az) f = d.y > 0 ? 2 : 3;
  else f = d.z > 0 ? 4 : 5;
  const float dist = std::max({ax, ay, az});
  const float texel = 2.0f * dist / size;  // a 90-degree face spans 2 * distance at that distance
  return lookup(faces_[f], p + n * (settings_.normal_offset * texel), texel);
}

}  // namespace cgsr
