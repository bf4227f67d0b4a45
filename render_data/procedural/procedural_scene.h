#pragma once
// The "procedural" scene source: game-like levels generated from a few YAML options and a seed.
//
//   scene:
//     type: procedural
//     layout: room          # room | corridors | hall | arena | outdoor | random
//     size: [10, 8]         # grid cells along x and z
//     cell: 2.5             # metres per cell
//     props: {crates: 6, pillars: 4, spheres: 3, tori: 2, stairs: 1, fences: 2, railings: 2, wires: 4, signs: 3}
//     camera: {steps: 12, eye_height: 1.6, vfov: 70, yaw_sway: 20, speed_variation: 0.5}
//
// A level is a grid of cells: walls (room perimeter and partitions, a maze of corridors, or the
// low boundary of an open arena under the sky) and free cells. The camera path is a random walk
// over free cells, smoothed by the Catmull-Rom path of scene.h, with yaw/pitch/roll sway and
// speed changes; props are placed only in cells the path does not visit, so the camera never
// passes through geometry. Same options + seed = same scene.
//
// Variety (procedural_variety.h): with a `variety` block (or `layout: random`) the layout, size,
// heights, prop counts, material families and colours, pattern scale, lights, fog and sky are
// drawn from the seed within the block's ranges, so one config gives a different level per seed;
// `variant: N` picks another level of the same config and seed (scene sets list several).

#include <cstdint>
#include <string>
#include <vector>

#include "core/config.h"
#include "render_data/scene.h"
#include "render_data/scene_source.h"

namespace cgsr {

// The level's plan: room | corridors | hall | arena | outdoor, or random (drawn from
// variety.layouts by the seed; a level is never built as random).
enum class ProceduralLayout { Room, Corridors, Hall, Arena, Outdoor, Random };
template <>
struct EnumNames<ProceduralLayout> {
  static constexpr const char* kind = "procedural layout";
  static const std::vector<std::string>& names();  // room, corridors, hall, arena, outdoor, random
};

struct ProceduralProps {
  int crates = 6, pillars = 4, spheres = 3, tori = 2, stairs = 1, fences = 2, railings = 2, wires = 4, signs = 3;
  int grates = 0;  // free-standing grate panels (alpha-tested bars), thin like fences
};

// Ranges the level's options are drawn from (procedural_variety.h); every [lo, hi] is inclusive.
struct ProceduralVariety {
  bool enabled = false;  // set when the scene block has `variety` or `layout: random`
  std::vector<ProceduralLayout> layouts = {ProceduralLayout::Room, ProceduralLayout::Corridors, ProceduralLayout::Hall,
                                          ProceduralLayout::Arena, ProceduralLayout::Outdoor};  // for layout: random
  std::vector<int> size = {7, 14};                   // grid cells per side
  std::vector<std::string> materials = {"bricks", "tiles", "checker", "noise", "planks", "glyphs", "plates",
                                        "stripes", "grate", "grid",  "tread",   "hexes"};  // texture families
  std::vector<float> pattern_scale = {0.6f, 2.0f};   // texel density multiplier (coarser .. finer patterns)
  std::vector<float> brightness = {0.35f, 2.0f};     // multiplier of every light and the ambient
  std::vector<int> lights = {1, 7};                  // point lights
  float coloured_lights = 0.5f;                      // chance that a lamp has a saturated colour
  float fog = 0.35f;                                 // chance of distance fog
  std::vector<float> fog_density = {0.01f, 0.06f};   // per metre
  std::vector<float> props = {0.5f, 1.5f};           // multiplier of the solid props' counts
  std::vector<float> thin = {1.0f, 3.0f};            // multiplier of fences, railings, wires, grates
};

struct ProceduralLighting {
  int point_lights = 3;       // lamps under the ceiling (rooms, corridors) or on poles (arena)
  float point_intensity = 2.5f;
  bool sun = false;           // a directional light (always on in arenas)
  float sun_intensity = 1.6f;
  bool shadows = true;        // lights cast shadows (when the render enables shadow maps)
  float ambient = 0.07f;      // linear ambient level
};

struct ProceduralCamera {
  int steps = 12;             // cells visited by the walk (path length)
  float eye_height = 1.6f;    // metres above the floor
  float vfov = 70.0f;         // vertical field of view, degrees
  float near_plane = 0.05f;
  float far_plane = 300.0f;
  float yaw_sway = 20.0f;     // degrees of look-around on top of the walking direction
  float pitch_sway = 8.0f;    // degrees
  float roll = 2.0f;          // degrees
  float speed_variation = 0.5f;  // relative: speeds vary in [1 - v, 1 + v]
};

struct ProceduralFog {
  float density = 0.0f;
  float start = 0.0f;
  std::vector<float> color = {0.5f, 0.55f, 0.6f};
};

struct ProceduralOptions {
  std::string name = "procedural";
  ProceduralLayout layout = ProceduralLayout::Room;
  int variant = 0;           // 0: the level of the render seed; N: another level from the same seed
  std::vector<int> size = {10, 8};
  float cell = 2.5f;
  float height = 4.0f;       // wall height (arena: boundary wall height)
  bool ceiling = true;       // rooms and corridors: closed ceiling (arenas never have one)
  int texture_size = 128;    // texels per side of each procedural texture
  float texel_density = 100; // texels per metre on walls and floors (texture repeats accordingly)
  ProceduralProps props;
  ProceduralLighting lighting;
  ProceduralCamera camera;
  ProceduralFog fog;
  std::vector<float> sky_horizon = {0.55f, 0.65f, 0.8f};
  std::vector<float> sky_zenith = {0.15f, 0.3f, 0.65f};
  ProceduralVariety variety;
};

config::Schema<ProceduralOptions> procedural_schema();

// Builds the level (variety drawn first when enabled); throws cgsr::Error when the layout leaves
// no room for the camera walk or the props.
SceneBundle make_procedural_scene(const ProceduralOptions& options, uint64_t seed);

// The seed a level is built from: the render seed, mixed with `variant` when it is not 0.
uint64_t procedural_level_seed(const ProceduralOptions& options, uint64_t seed);

// Adds "procedural" to a scene-source registry (scene_sources() does, when it is first used).
void register_procedural_scene_source(Registry<SceneSourceFactory>& registry);

}  // namespace cgsr
