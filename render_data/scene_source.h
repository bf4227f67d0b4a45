#pragma once
// Scene sources by name: a factory takes the {type: Name, ...} block of a render config and a
// seed and returns the scene with its camera path. The registry fills itself with the built-in
// sources on first use: "procedural" (procedural_scene.h), "shapes" (procedural/shapes_scene.h)
// and "q3bsp" (q3/q3_scene_source.h).
//
//   scene:
//     type: procedural      # the registry key
//     layout: room          # everything else is the source's own options
//
//   SceneBundle bundle = make_scene(config_block, seed);

#include <cstdint>
#include <functional>

#include "core/config.h"
#include "core/registry.h"
#include "render_data/scene.h"

namespace cgsr {

// Parses the block's options (everything but `type`) and builds the scene; errors name the
// block's file position. The same block and seed give the same scene.
using SceneSourceFactory = std::function<SceneBundle(const config::Block& block, uint64_t seed)>;

// The process-wide table of scene sources, the built-in ones already in it.
Registry<SceneSourceFactory>& scene_sources();

// Looks up block.type, builds the scene, then validates the scene and its camera path.
SceneBundle make_scene(const config::Block& block, uint64_t seed);

}  // namespace cgsr
