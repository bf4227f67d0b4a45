#include "render_data/scene.h"

#include <cmath>
#include <limits>

#include "core/config.h"
#include "core/error.h"

namespace cgsr {
namespace {

// Catmull-Rom on non-uniform key times (the tangent at a key is the secant of its neighbours,
// scaled by time), so uneven key spacing changes speed smoothly instead of kinking the path.
double hermite(double p0, double p1, double m0, double m1, double s, double dt) {
  const double s2 = s * s, s3 = s2 * s;
  return (2 * s3 - 3 * s2 + 1) * p0 + (s3 - 2 * s2 + s) * dt * m0 + (-2 * s3 + 3 * s2) * p1 + (s3 - s2) * dt * m1;
}

bool finite(Vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
bool finite(Vec2 v) { return std::isfinite(v.x) && std::isfinite(v.y); }

}  // namespace

CameraPose CameraPath::at_time(double time) const {
  CGSR_CHECK(!keys.empty(), "camera path without keys");
  if (keys.size() == 1 || time <= keys.front().time) return keys.front().pose;
  if (time >= keys.back().time) return keys.back().pose;
  size_t i = 0;
  while (i + 2 < keys.size() && keys[i + 1].time <= time) ++i;
  const CameraKey& k1 = keys[i];
  const CameraKey& k2 = keys[i + 1];
  const CameraKey& k0 = i > 0 ? keys[i - 1] : k1;
  const CameraKey& k3 = i + 2 < keys.size() ? keys[i + 2] : k2;
  const double dt = k2.time - k1.time;
  const double s = (time - k1.time) / dt;

  // Each scalar of the pose is interpolated the same way.
  auto interp = [&](auto get) {
    const double p0 = get(k0.pose), p1 = get(k1.pose), p2 = get(k2.pose), p3 = get(k3.pose);
    const double m1 = (&k0 == &k1) ? (p2 - p1) / dt : (p2 - p0) / (k2.time - k0.time);
    const double m2 = (&k3 == &k2) ? (p2 - p1) / dt : (p3 - p1) / (k3.time - k1.time);
    return static_cast<float>(hermite(p1, p2, m1, m2, s, dt));
  };
  CameraPose out;
  out.position.x = interp([](const CameraPose& p) { return p.position.x; });
  out.position.y = interp([](const CameraPose& p) { return p.position.y; });
  out.position.z = interp([](const CameraPose& p) { return p.position.z; });
  out.yaw = interp([](const CameraPose& p) { return p.yaw; });
  out.pitch = interp([](const CameraPose& p) { return p.pitch; });
  out.roll = interp([](const CameraPose& p) { return p.roll; });
  out.vfov = interp([](const CameraPose& p) { return p.vfov; });
  return out;
}

CameraPose CameraPath::at_frame(int frame, int frames) const {
  CGSR_CHECK(frames >= 1, "camera path sampled with no frames");
  if (frames == 1) return at_time(keys.front().time);
  const double t0 = keys.front().time, t1 = keys.back().time;
  return at_time(t0 + (t1 - t0) * static_cast<double>(frame) / (frames - 1));
}

void validate_camera_path(const CameraPath& path, const std::string& context) {
  if (path.keys.empty()) throw Error(context, "the camera path has no keys");
  if (!(path.near_plane > 0) || !(path.far_plane > path.near_plane))
    throw Error(context, "camera planes need 0 < near < far, got near " + std::to_string(path.near_plane) +
                             ", far " + std::to_string(path.far_plane));
  for (size_t i = 0; i < path.keys.size(); ++i) {
    const auto& k = path.keys[i];
    const std::string where = context + ": camera key " + std::to_string(i);
    if (!std::isfinite(k.time) || !finite(k.pose.position) || !std::isfinite(k.pose.yaw) ||
        !std::isfinite(k.pose.pitch) || !std::isfinite(k.pose.roll))
      throw Error(where, "has a non-finite value");
    if (!(k.pose.vfov > 1 && k.pose.vfov < 179)) throw Error(where, "vertical field of view must be in (1, 179) degrees");
    if (i > 0 && !(k.time > path.keys[i - 1].time)) throw Error(where, "key times must increase strictly");
  }
}

void validate_scene(const Scene& scene) {
  const std::string ctx = "scene '" + scene.name + "'";
  for (size_t t = 0; t < scene.textures.size(); ++t) {
    const auto& tex = scene.textures[t];
    const std::string where = ctx + ": texture " + std::to_string(t) + " '" + tex.name + "'";
    if (tex.width <= 0 || tex.height <= 0) throw Error(where, "has no pixels");
    if (tex.channels != 3 && tex.channels != 4) throw Error(where, "must have 3 or 4 channels");
    if (tex.data.size() != static_cast<size_t>(tex.width) * tex.height * tex.channels)
      throw Error(where, "data size " + std::to_string(tex.data.size()) + " does not match " +
                             std::to_string(tex.width) + "x" + std::to_string(tex.height) + "x" +
                             std::to_string(tex.channels));
  }
  auto check_texture = [&](int index, const std::string& where) {
    if (index < -1 || index >= static_cast<int>(scene.textures.size()))
      throw Error(where, "texture index " + std::to_string(index) + " out of range (" +
                             std::to_string(scene.textures.size()) + " textures)");
  };
  for (size_t m = 0; m < scene.materials.size(); ++m) {
    const auto& mat = scene.materials[m];
    const std::string where = ctx + ": material " + std::to_string(m) + " '" + mat.name + "'";
    check_texture(mat.albedo_texture, where);
    check_texture(mat.lightmap_texture, where);
    if (!finite(mat.tint) || !std::isfinite(mat.lightmap_scale) || !std::isfinite(mat.specular) ||
        !(mat.shininess >= 0) || !std::isfinite(mat.shininess))
      throw Error(where, "has a non-finite or negative value");
    if (mat.alpha_cutoff > 0 && mat.albedo_texture >= 0 && scene.textures[mat.albedo_texture].channels != 4)
      throw Error(where, "alpha_cutoff needs an RGBA albedo texture");
  }
  for (size_t i = 0; i < scene.meshes.size(); ++i) {
    const auto& mesh = scene.meshes[i];
    const std::string where = ctx + ": mesh " + std::to_string(i) + " '" + mesh.name + "'";
    const size_t n = mesh.positions.size();
    if (mesh.normals.size() != n) throw Error(where, "needs one normal per vertex");
    if (mesh.uvs.size() != n) throw Error(where, "needs one uv per vertex");
    if (!mesh.lightmap_uvs.empty() && mesh.lightmap_uvs.size() != n)
      throw Error(where, "lightmap_uvs must be empty or one per vertex");
    if (!mesh.colors.empty() && mesh.colors.size() != n) throw Error(where, "colors must be empty or one per vertex");
    if (mesh.indices.size() % 3 != 0) throw Error(where, "index count is not a multiple of 3");
    for (uint32_t idx : mesh.indices)
      if (idx >= n) throw Error(where, "index " + std::to_string(idx) + " out of range (" + std::to_string(n) + " vertices)");
    if (mesh.material < 0 || mesh.material >= static_cast<int>(scene.materials.size()))
      throw Error(where, "material index " + std::to_string(mesh.material) + " out of range");
    if (mesh.object_id < 0) throw Error(where, "object_id " + config::out_of_range(mesh.object_id, 0, config::kUnbounded));
    if (scene.materials[mesh.material].lightmap_texture >= 0 && mesh.lightmap_uvs.empty())
      throw Error(where, "its material has a lightmap but the mesh has no lightmap_uvs");
    for (size_t v = 0; v < n; ++v)
      if (!finite(mesh.positions[v]) || !finite(mesh.normals[v]) || !finite(mesh.uvs[v]) ||
          (!mesh.lightmap_uvs.empty() && !finite(mesh.lightmap_uvs[v])))
        throw Error(where, "vertex " + std::to_string(v) + " has a non-finite attribute");
  }
  for (size_t l = 0; l < scene.lights.size(); ++l) {
    const auto& light = scene.lights[l];
    const std::string where = ctx + ": light " + std::to_string(l);
    if (!finite(light.position) || !finite(light.color) || !std::isfinite(light.intensity) || !(light.radius > 0))
      throw Error(where, "needs finite values and radius > 0");
    if (light.type == LightType::Directional && !(length(light.direction) > 0))
      throw Error(where, "a directional light needs a non-zero direction");
  }
  if (!(scene.fog.density >= 0) || !std::isfinite(scene.fog.density))
    throw Error(ctx, "fog density " + config::out_of_range(scene.fog.density, 0, config::kUnbounded));
}

void scene_bounds(const Scene& scene, Vec3& lo, Vec3& hi) {
  const float inf = std::numeric_limits<float>::infinity();
  lo = {inf, inf, inf};
  hi = {-inf, -inf, -inf};
  for (const auto& mesh : scene.meshes)
    for (const auto& p : mesh.positions) {
      lo = min(lo, p);
      hi = max(hi, p);
    }
}

size_t triangle_count(const Scene& scene) {
  size_t n = 0;
  for (const auto& mesh : scene.meshes) n += mesh.indices.size() / 3;
  return n;
}

}  // namespace cgsr
