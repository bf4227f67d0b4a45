#include "render_data/scene_source.h"

#include "render_data/procedural/procedural_scene.h"
#include "render_data/procedural/shapes_scene.h"
#include "render_data/q3/q3_scene_source.h"

namespace cgsr {

Registry<SceneSourceFactory>& scene_sources() {
  static Registry<SceneSourceFactory> registry = [] {
    Registry<SceneSourceFactory> r("scene source");
    register_procedural_scene_source(r);
    register_shapes_scene_source(r);
    q3::register_q3_scene_source(r);
    return r;
  }();
  return registry;
}

SceneBundle make_scene(const config::Block& block, uint64_t seed) {
  const std::string type = config::block_type(block);
  SceneBundle bundle = scene_sources().get(type)(block, seed);
  validate_scene(bundle.scene);
  validate_camera_path(bundle.camera, "scene '" + bundle.scene.name + "'");
  return bundle;
}

}  // namespace cgsr
