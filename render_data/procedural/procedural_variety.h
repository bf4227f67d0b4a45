#pragma once
// Procedural variety: one scene config that gives a different level per seed. The `variety`
// block of a procedural scene holds ranges; draw_variety() picks the level's concrete options
// from them (layout, size, wall height, prop counts, lights, fog, sky, pattern scale), and the
// level builder then draws materials from the texture families with random colours and gives
// lamps random colours.
//
//   scene:
//     type: procedural
//     layout: random                 # drawn from variety.layouts (or name one layout)
//     variety:
//       layouts: [room, corridors, hall, arena, outdoor]
//       size: [7, 14]                # cells per side
//       materials: [bricks, plates, grate, noise, glyphs, stripes, checker, grid, tread, hexes]
//       pattern_scale: [0.6, 2.0]    # texel density multiplier: coarser .. finer patterns
//       brightness: [0.35, 2.0]      # dark .. bright scenes
//       lights: [1, 7]
//       coloured_lights: 0.5         # chance per lamp
//       fog: 0.35                    # chance of fog, density drawn from fog_density
//       fog_density: [0.01, 0.06]
//       props: [0.5, 1.5]            # multiplier of crates, pillars, spheres, tori, stairs, signs
//       thin: [1.0, 3.0]             # multiplier of fences, railings, wires, grates
//
// The config's own props, lighting and texel_density are the base the multipliers apply to.

#include <cstdint>

#include "core/config.h"
#include "render_data/procedural/procedural_rng.h"
#include "render_data/procedural/procedural_scene.h"
#include "render_data/vec_math.h"

namespace cgsr {

config::Schema<ProceduralVariety> variety_schema();

// The options of the level for `seed`: every drawn option filled in, variety.enabled kept (the
// builder's own draws depend on it). Options without variety are returned unchanged.
ProceduralOptions draw_variety(const ProceduralOptions& options, uint64_t seed);

// Linear RGB from hue (turns, any real), saturation and value in [0, 1].
Vec3 hsv_colour(float hue, float saturation, float value);

// A random albedo pair (base, accent) for a texture family: muted or saturated hues, the accent
// darker or lighter than the base so patterns keep their contrast.
void random_albedo(ProceduralRng& rng, Vec3& base, Vec3& accent);

}  // namespace cgsr
