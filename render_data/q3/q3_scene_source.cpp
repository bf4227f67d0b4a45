#include "render_data/q3/q3_scene_source.h"

#include <spdlog/spdlog.h>

#include <chrono>

#include "core/error.h"
#include "core/text.h"
#include "render_data/q3/bsp_file.h"
#include "render_data/q3/bsp_trace.h"
#include "render_data/q3/entities.h"
#include "render_data/q3/game_data.h"
#include "render_data/q3/pk3_archive.h"
#include "render_data/q3/shader_script.h"
#include "render_data/q3/surface_obstacles.h"

namespace cgsr::q3 {
namespace {

config::Schema<Q3CameraOptions> camera_schema() {
  config::Schema<Q3CameraOptions> s;
  s.field("length", &Q3CameraOptions::length, "game units the camera travels over the sequence").range(64, 1e6);
  s.field("eye_height", &Q3CameraOptions::eye_height, "eye above the player origin (24 above the floor)")
      .range(0, 64);
  s.field("look_ahead", &Q3CameraOptions::look_ahead, "the camera looks at the path this far ahead")
      .range(1, 4096);
  s.field("yaw_sway", &Q3CameraOptions::yaw_sway, "amplitude of the yaw sway, degrees").range(0, 90);
  s.field("pitch_sway", &Q3CameraOptions::pitch_sway, "amplitude of the pitch sway, degrees").range(0, 45);
  s.field("max_link", &Q3CameraOptions::max_link, "longest straight hop between waypoints, game units")
      .range(64, 16384);
  s.field("vfov", &Q3CameraOptions::vfov, "vertical field of view, degrees").range(10, 150);
  s.field("near_plane", &Q3CameraOptions::near_plane, "near clip plane, game units").range(0.5, 64);
  s.field("far_plane", &Q3CameraOptions::far_plane, "far clip plane, game units").range(256, 1e6);
  return s;
}

float to_f(double v) { return static_cast<float>(v); }

}  // namespace

config::Schema<Q3SceneOptions> q3_scene_schema() {
  config::Schema<Q3SceneOptions> s;
  s.field("map", &Q3SceneOptions::map, "map name (maps/<map>.bsp) or path inside the pk3 files").required();
  s.field("data_root", &Q3SceneOptions::data_root,
          "OpenArena data directory (baseoa/ and other game dirs); empty: only the pk3 list");
  s.field("pk3", &Q3SceneOptions::pk3, "extra pk3 archives, mounted last (they override)");
  s.field("patch_level", &Q3SceneOptions::patch_level, "quads per side of each Bezier patch").range(1, 32);
  s.field("overbright_bits", &Q3SceneOptions::overbright_bits, "the game's r_overBrightBits").range(0, 2);
  s.field("map_overbright_bits", &Q3SceneOptions::map_overbright_bits, "the game's r_mapOverBrightBits")
      .range(0, 4);
  s.field("unit_scale", &Q3SceneOptions::unit_scale, "metres per game unit").range(1e-4, 10);
  s.section("camera", &Q3SceneOptions::camera, camera_schema(), "camera path through the level");
  s.validate([](const Q3SceneOptions& o, const config::Cursor& at, const YAML::Node& node) {
    if (!(o.camera.far_plane > o.camera.near_plane)) at.child("camera").fail(node, "far_plane must exceed near_plane");
  });
  return s;
}

Vec3 quake_to_scene(Vec3 q, float unit_scale) { return Vec3{q.x, q.z, -q.y} * unit_scale; }

CameraPose quake_to_scene_pose(const QuakeCameraKey& key, float unit_scale, float vfov) {
  CameraPose pose;
  pose.position = quake_to_scene(key.position, unit_scale);
  // Quake yaw 90 looks along +y (scene -z), the scene's yaw 0.
  pose.yaw = key.yaw - 90.0f;
  pose.pitch = key.pitch;
  pose.vfov = vfov;
  return pose;
}

SceneBundle load_q3_scene(const Q3SceneOptions& options, uint64_t seed, Q3SceneReport* report_out) {
  const auto began = std::chrono::steady_clock::now();
  Q3SceneReport report;
  const auto files = mount_game_data({options.data_root, options.pk3});
  report.archives = files->archive_count();
  const std::string path = map_path(options.map);
  const auto bytes = files->try_read(path);
  if (!bytes) {
    const auto maps = files->list("maps/", ".bsp");
    std::vector<std::string> names;
    for (const auto& m : maps) names.push_back(m.substr(5, m.size() - 9));
    throw Error(options.map, path + " is in none of the " + std::to_string(files->archive_count()) +
                                 " pk3 archives" + did_you_mean(options.map, names) + "; maps found: " +
                                 (names.empty() ? "none" : join(names)) + ". The OpenArena maps come with " +
                                 kOpenArenaPackages + " (" + kOpenArenaInstall + ")");
  }
  report.bsp = files->describe(path);
  const BspFile bsp = parse_bsp(*bytes, path);

  ShaderLibrary shaders;
  shaders.add_all_scripts(*files);
  report.shader_scripts_problems = shaders.problems().size();

  Q3LevelOptions level_options;
  level_options.patch_level = options.patch_level;
  level_options.overbright_bits = options.overbright_bits;
  level_options.map_overbright_bits = options.map_overbright_bits;
  Q3Level level = build_level(bsp, shaders, *files, level_options);
  report.level = level.stats;

  // The camera path, in Quake space, against brushes and every drawn triangle.
  std::vector<std::array<Vec3, 3>> triangles;
  for (const Mesh& mesh : level.scene.meshes)
    for (size_t k = 0; k + 2 < mesh.indices.size(); k += 3)
      triangles.push_back({mesh.positions[mesh.indices[k]], mesh.positions[mesh.indices[k + 1]],
                           mesh.positions[mesh.indices[k + 2]]});
  const SurfaceObstacles obstacles(std::move(triangles));
  const BspCollision collision(bsp);
  const std::vector<Entity> entities = parse_entities(bsp.entities, path + ": entities");
  CameraPathOptions path_options;
  path_options.length = to_f(options.camera.length);
  path_options.eye_height = to_f(options.camera.eye_height);
  path_options.look_ahead = to_f(options.camera.look_ahead);
  path_options.yaw_sway_degrees = to_f(options.camera.yaw_sway);
  path_options.pitch_sway_degrees = to_f(options.camera.pitch_sway);
  path_options.max_link = to_f(options.camera.max_link);
  path_options.seed = seed;
  const QuakeCameraPath quake_path = build_camera_path(entities, collision, obstacles, path_options, path);
  report.path = quake_path.report;

  // Quake space -> scene space, here only.
  SceneBundle bundle;
  bundle.scene = std::move(level.scene);
  bundle.scene.name = options.map;
  const float scale = to_f(options.unit_scale);
  for (Mesh& mesh : bundle.scene.meshes) {
    for (Vec3& p : mesh.positions) p = quake_to_scene(p, scale);
    for (Vec3& n : mesh.normals) n = normalize(quake_to_scene(n, 1.0f));
  }
  for (const QuakeCameraKey& key : quake_path.keys)
    bundle.camera.keys.push_back({key.distance, quake_to_scene_pose(key, scale, to_f(options.camera.vfov))});
  bundle.camera.near_plane = to_f(options.camera.near_plane) * scale;
  bundle.camera.far_plane = to_f(options.camera.far_plane) * scale;

  const Q3LevelStats& s = report.level;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
  spdlog::info("q3bsp {} ({} archives): {} faces: drawn {} polygons, {} patches ({} triangles at level {}), {} meshes; "
               "{} sky; skipped {} billboards, {} invisible, {} transparent; {} triangles, {} textures, {} images "
               "missing, {} undecodable; loaded in {:.1f} s",
               report.bsp, report.archives, s.faces, s.polygons, s.patches, s.patch_triangles, options.patch_level,
               s.meshes, s.sky_faces, s.skipped_billboards, s.skipped_invisible, s.skipped_transparent, s.triangles,
               s.textures_loaded, s.missing_images.size(), s.undecodable_images.size(), seconds);
  if (!s.missing_images.empty()) spdlog::warn("q3bsp {}: images not found (drawn grey): {}", path, join(s.missing_images));
  if (s.non_finite_coordinates > 0)
    spdlog::warn("q3bsp {}: {} non-finite texture coordinates set to 0", path, s.non_finite_coordinates);
  spdlog::info("q3bsp {} camera path: {}", path, report.path.summary());
  if (report_out) *report_out = std::move(report);
  return bundle;
}

void register_q3_scene_source(Registry<SceneSourceFactory>& registry) {
  registry.add(
      "q3bsp",
      [](const config::Block& block, uint64_t seed) {
        return load_q3_scene(config::parse_block_options(block, q3_scene_schema()), seed);
      },
      "a Quake III / OpenArena map (IBSP v46) from the installed pk3 archives");
}

}  // namespace cgsr::q3
