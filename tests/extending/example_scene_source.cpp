// The scene source of docs/extending.md: a box room with a crate in it, the camera circling the
// crate. Its config block:
//
//   scene: {type: box, size: [6, 3, 8], crate: 1.2}
#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "render_data/scene_source.h"

namespace cgsr {

struct BoxOptions {
  std::vector<float> size = {6, 3, 8};  // the room, metres: width, height, depth
  float crate = 1.0f;                   // the crate's edge, metres
};

config::Schema<BoxOptions> box_schema() {
  config::Schema<BoxOptions> s;
  s.field("size", &BoxOptions::size, "the room's width, height and depth, metres")
      .range(1, 100)
      .check([](const std::vector<float>& v) { return v.size() == 3; }, "must be [width, height, depth]");
  s.field("crate", &BoxOptions::crate, "the crate's edge, metres").range(0.1, 2);
  return s;
}

// An axis-aligned box from `lo` to `hi` as one mesh; `inside` turns its faces inwards (a room).
Mesh box_mesh(const std::string& name, Vec3 lo, Vec3 hi, bool inside, int material, int object_id) {
  Mesh mesh;
  mesh.name = name;
  mesh.material = material;
  mesh.object_id = object_id;
  for (int axis = 0; axis < 3; ++axis)
    for (float side : {-1.0f, 1.0f}) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;  // u x v points along +axis
      const float facing = inside ? -side : side;
      Vec3 normal;
      normal[axis] = facing;
      const auto base = static_cast<uint32_t>(mesh.positions.size());
      for (const auto& [a, b] : {std::pair{0, 0}, std::pair{1, 0}, std::pair{1, 1}, std::pair{0, 1}}) {
        Vec3 p;
        p[axis] = side < 0 ? lo[axis] : hi[axis];
        p[u] = a ? hi[u] : lo[u];
        p[v] = b ? hi[v] : lo[v];
        mesh.positions.push_back(p);
        mesh.normals.push_back(normal);
        mesh.uvs.push_back({static_cast<float>(a), static_cast<float>(b)});
      }
      // Counter-clockwise seen from the side the normal points to (scene.h).
      const bool flip = facing < 0;
      for (uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) mesh.indices.push_back(base + (flip ? (4 - i) % 4 : i));
    }
  return mesh;
}

SceneBundle make_box_scene(const BoxOptions& o, uint64_t seed) {
  SceneBundle bundle;
  Scene& scene = bundle.scene;
  scene.name = "box";
  scene.materials = {Material{"walls"}, Material{"crate"}};
  scene.materials[0].tint = {0.7f, 0.65f, 0.6f};
  scene.materials[1].tint = {0.6f, 0.35f, 0.15f};
  const float w = o.size[0] / 2, h = o.size[1], d = o.size[2] / 2, c = o.crate / 2;
  scene.meshes.push_back(box_mesh("room", {-w, 0, -d}, {w, h, d}, /*inside=*/true, 0, 0));
  scene.meshes.push_back(box_mesh("crate", {-c, 0, -c}, {c, o.crate, c}, /*inside=*/false, 1, 1));
  Light light;
  light.position = {0, h * 0.9f, 0};
  light.intensity = 2;
  scene.lights.push_back(light);
  // Circling the crate at eye height, halfway to the walls; the seed picks where the circle starts.
  const float radius = 0.5f * std::min(w, d) + 0.5f * c, start = static_cast<float>(seed % 360);
  for (int k = 0; k <= 4; ++k) {
    const float angle = start + 90.0f * k, rad = angle * static_cast<float>(M_PI) / 180.0f;
    CameraPose pose;
    pose.position = {radius * std::sin(rad), std::min(1.6f, 0.8f * h), radius * std::cos(rad)};
    pose.yaw = angle;  // yaw 0 looks along -z: towards the centre from +z
    pose.pitch = -10;
    bundle.camera.keys.push_back({static_cast<double>(k), pose});
  }
  bundle.camera.far_plane = 2 * (w + d + h);
  return bundle;
}

void register_box_scene_source(Registry<SceneSourceFactory>& registry) {
  registry.add(
      "box",
      [](const config::Block& block, uint64_t seed) {
        return make_box_scene(config::parse_block_options(block, box_schema()), seed);
      },
      "a box room with a crate, the camera circling it (docs/extending.md)");
}

}  // namespace cgsr
