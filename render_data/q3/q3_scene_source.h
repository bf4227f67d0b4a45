#pragma once
// The "q3bsp" scene source: a Quake III / OpenArena map from the installed pk3 archives, with a
// camera path through it.
//
//   scene:
//     type: q3bsp
//     map: oa_dm1                 # maps/oa_dm1.bsp in the game's pk3 files
//     patch_level: 8
//     camera: {length: 2400, vfov: 73.74}
//
// Coordinates: Quake space (x, y, z; Z up; game units) becomes scene space (+y up, right-handed,
// metres) in quake_to_scene below and nowhere else: (x, y, z) -> (x, z, -y) * unit_scale, a
// proper rotation (windings and handedness are kept). A Quake yaw (counter-clockwise from +x)
// becomes the scene's yaw (0 looks along -z = Quake +y) minus 90 degrees; pitch is unchanged.

#include <cstdint>
#include <string>
#include <vector>

#include "core/config.h"
#include "render_data/q3/camera_path.h"
#include "render_data/q3/q3_level.h"
#include "render_data/scene_source.h"

namespace cgsr::q3 {

struct Q3CameraOptions {
  double length = 2400;         // game units of travel over the whole sequence
  double eye_height = 26;       // above the player origin
  double look_ahead = 160;      // game units
  double yaw_sway = 20;         // degrees
  double pitch_sway = 8;        // degrees
  double max_link = 1536;       // longest straight hop between waypoints, game units
  double vfov = 73.74;          // degrees: the game's 90 degree horizontal fov at 4:3
  double near_plane = 4;        // game units (the game's r_znear)
  double far_plane = 6144;      // game units
};

struct Q3SceneOptions {
  std::string map;                                // "oa_dm1" or "maps/oa_dm1.bsp"
  std::string data_root = "/usr/share/games/openarena";  // "" reads only `pk3`
  std::vector<std::string> pk3;                   // extra archives, mounted last (they override)
  int patch_level = 8;
  int overbright_bits = 1;
  int map_overbright_bits = 2;
  double unit_scale = 1.0 / 32;                   // metres per game unit (a player is 1.75 m)
  Q3CameraOptions camera;
};

config::Schema<Q3SceneOptions> q3_scene_schema();

struct Q3SceneReport {
  std::string bsp;  // "pak1-maps.pk3:maps/oa_dm1.bsp"
  size_t archives = 0;
  size_t shader_scripts_problems = 0;
  Q3LevelStats level;
  CameraPathReport path;
};

// Loads the map and lays out the camera path. `seed` varies the start and the sways.
SceneBundle load_q3_scene(const Q3SceneOptions& options, uint64_t seed, Q3SceneReport* report = nullptr);

// The one place where Quake space becomes scene space (see above).
Vec3 quake_to_scene(Vec3 quake, float unit_scale);
CameraPose quake_to_scene_pose(const QuakeCameraKey& key, float unit_scale, float vfov);

// Adds "q3bsp" to `registry` (scene_source.h).
void register_q3_scene_source(Registry<SceneSourceFactory>& registry);

}  // namespace cgsr::q3
