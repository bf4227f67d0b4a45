#pragma once
// Small hand-built scenes for the render_data tests.

#include <cmath>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "core/config.h"
#include "core/error.h"
#include "render_data/dataset_manifest.h"
#include "render_data/render_job.h"
#include "render_data/renderer.h"
#include "render_data/scene.h"
#include "render_data/scene_source.h"
#include "tests/support/scratch_dir.h"

namespace cgsr::test {

// One untextured material (white, matte) and a light so shading is non-trivial.
inline Scene empty_scene(const std::string& name = "test") {
  Scene s;
  s.name = name;
  Material m;
  m.name = "white";
  s.materials.push_back(m);
  Light l;
  l.type = LightType::Directional;
  l.direction = {0.3f, -1.0f, -0.2f};
  s.lights.push_back(l);
  return s;
}

// A triangle with a constant normal (facing the camera when counter-clockwise seen from it).
inline void add_triangle(Scene& s, Vec3 a, Vec3 b, Vec3 c, int object_id) {
  Mesh m;
  m.name = "triangle" + std::to_string(object_id);
  m.positions = {a, b, c};
  const Vec3 n = normalize(cross(b - a, c - a));
  m.normals = {n, n, n};
  m.uvs = {{0, 0}, {1, 0}, {0, 1}};
  m.indices = {0, 1, 2};
  m.object_id = object_id;
  s.meshes.push_back(m);
}

// A quad centre + u + v (counter-clockwise seen from the side cross(u, v) points to).
inline void add_quad(Scene& s, Vec3 centre, Vec3 u, Vec3 v, int object_id) {
  Mesh m;
  m.name = "quad" + std::to_string(object_id);
  m.positions = {centre - u - v, centre + u - v, centre + u + v, centre - u + v};
  const Vec3 n = normalize(cross(u, v));
  m.normals = {n, n, n, n};
  m.uvs = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};
  m.indices = {0, 1, 2, 0, 2, 3};
  m.object_id = object_id;
  s.meshes.push_back(m);
}


// A render config as `cgsr render` reads it (its run settings included).
struct SceneConfig : RenderJobOptions {
  int64_t seed = 0;
  int threads = 0;
};

inline config::Schema<SceneConfig> scene_config_schema() {
  config::Schema<SceneConfig> s;
  add_render_job_fields(s);
  s.field("seed", &SceneConfig::seed, "seed");
  s.field("threads", &SceneConfig::threads, "threads");
  return s;
}

// The scene of a {type: ..., ...} block given as YAML text (errors name "test.yaml").
inline SceneBundle build_scene(const std::string& yaml, uint64_t seed) {
  const auto doc = config::Document::parse(yaml, "test.yaml");
  config::Block block{doc.root(), std::make_shared<config::Document>(doc), ""};
  return make_scene(block, seed);
}

// Renderer settings for the small scenes: no shadow maps (their lights need none), small tiles.
inline RenderSettings unshadowed() {
  RenderSettings s;
  s.shadows = false;
  s.tile_size = 8;
  return s;
}

}  // namespace cgsr::test

#include <torch/torch.h>

#include "render_data/dataset_manifest.h"
#include "render_data/frame_files.h"
#include "render_data/gbuffer.h"

namespace cgsr::test {

// A G-buffer filled with simple valid values: a plane at depth `depth` facing the camera.
inline GBuffer flat_gbuffer(int W, int H, float depth = 5.0f) {
  GBuffer g;
  g.width = W;
  g.height = H;
  g.color = torch::rand({3, H, W});
  g.depth = torch::full({1, H, W}, depth);
  g.normal = torch::zeros({3, H, W});
  g.normal[2].fill_(1.0f);
  g.normal_angle = torch::zeros({1, H, W});
  g.object_id = torch::zeros({1, H, W}, torch::kInt32);
  g.material_id = torch::zeros({1, H, W}, torch::kInt32);
  g.edge = torch::zeros({1, H, W});
  g.motion = torch::zeros({2, H, W});
  return g;
}

// Writes a complete dataset in the cgsr format; `make(frame, resolution)` gives each G-buffer.
template <class Make>
DatasetManifest write_test_dataset(const std::filesystem::path& dir, int frames, std::vector<Resolution> resolutions,
                                   Make make, double near_plane = 0.1, double far_plane = 100.0) {
  DatasetManifest m;
  m.name = "synthetic";
  m.complete = true;
  m.fingerprint = "test";
  m.frames = frames;
  m.resolutions = resolutions;
  m.near_plane = near_plane;
  m.far_plane = far_plane;
  m.split = make_split(frames);
  for (int f = 0; f < frames; ++f)
    for (const auto& r : resolutions) write_frame_files(dir, r, f, make(f, r));
  write_manifest(dir, m);
  return m;
}

// A two-frame manifest's fixed part (32x24 and 64x48), to which a test appends one block.
inline const std::string& manifest_head() {
  static const std::string head =
      "format: cgsr-dataset\nversion: 1\nname: x\ncomplete: true\nfingerprint: a\nframes: 2\n"
      "resolutions: [32x24, 64x48]\nnear: 0.1\nfar: 10\nsplit: {train: [0, 1], val: [], test: []}\n";
  return head;
}

// Each (block, message): manifest_head() plus the block must fail to read with an error that names
// the manifest at `at` ("manifest.yaml:11"), contains `key` and the message.
inline void expect_manifest_errors(const std::filesystem::path& dir,
                                   const std::vector<std::pair<std::string, std::string>>& cases,
                                   const std::string& at, const std::string& key) {
  for (const auto& [block, message] : cases) {
    std::ofstream(dir / "manifest.yaml", std::ios::trunc) << manifest_head() << block << "\n";
    try {
      read_manifest(dir);
      ADD_FAILURE() << "expected an error for " << block;
    } catch (const Error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(at), std::string::npos) << what;
      EXPECT_NE(what.find(key), std::string::npos) << what;
      EXPECT_NE(what.find(message), std::string::npos) << what;
    }
  }
}

}  // namespace cgsr::test
