// The procedural scene source: determinism, every shipped scene config, a camera that never
// passes through geometry, and tileable textures.
#include <gtest/gtest.h>

#include <filesystem>

#include "core/config.h"
#include "core/error.h"
#include "render_data/procedural/procedural_scene.h"
#include "render_data/procedural/procedural_textures.h"
#include "render_data/render_job.h"
#include "render_data/scene_source.h"

namespace cgsr {
namespace {
namespace fs = std::filesystem;

// A render config as `cgsr render` reads it (its run settings included).
struct SceneConfig : RenderJobOptions {
  int64_t seed = 0;
  int threads = 0;
};

config::Schema<SceneConfig> scene_config_schema() {
  config::Schema<SceneConfig> s;
  add_render_job_fields(s);
  s.field("seed", &SceneConfig::seed, "seed");
  s.field("threads", &SceneConfig::threads, "threads");
  return s;
}

SceneBundle build(const std::string& yaml, uint64_t seed) {
  const auto doc = config::Document::parse(yaml, "test.yaml");
  config::Block block{doc.root(), std::make_shared<config::Document>(doc), ""};
  return make_scene(block, seed);
}

TEST(ProceduralScene, SameSeedSameSceneOtherSeedOtherScene) {
  const std::string yaml = "type: procedural\nlayout: room\nsize: [12, 10]\ntexture_size: 32\n";
  const auto a = build(yaml, 5), b = build(yaml, 5), c = build(yaml, 6);
  ASSERT_EQ(a.scene.meshes.size(), b.scene.meshes.size());
  for (size_t m = 0; m < a.scene.meshes.size(); ++m) {
    ASSERT_EQ(a.scene.meshes[m].positions.size(), b.scene.meshes[m].positions.size());
    for (size_t v = 0; v < a.scene.meshes[m].positions.size(); ++v)
      ASSERT_EQ(a.scene.meshes[m].positions[v].x, b.scene.meshes[m].positions[v].x);
  }
  EXPECT_EQ(a.scene.textures[0].data, b.scene.textures[0].data);
  bool differs = a.camera.keys.size() != c.camera.keys.size();
  for (size_t k = 0; !differs && k < a.camera.keys.size(); ++k)
    differs = a.camera.keys[k].pose.position.x != c.camera.keys[k].pose.position.x;
  EXPECT_TRUE(differs);
}

TEST(ProceduralScene, UnknownOptionIsAnErrorWithItsPosition) {
  try {
    build("type: procedural\nlayuot: room\n", 1);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("test.yaml:2"), std::string::npos) << what;
    EXPECT_NE(what.find("did you mean 'layout'"), std::string::npos) << what;
  }
}

TEST(ProceduralScene, TooManyPropsForTheRoomIsAnError) {
  EXPECT_THROW(build("type: procedural\nsize: [4, 4]\nprops: {crates: 40}\n", 1), Error);
}

// The camera must not be inside any prop or wall: check every mesh's bounding box (shrunk a
// little, boxes of thin things are fine to touch) against camera positions along the path.
void expect_camera_in_free_space(const SceneBundle& b, const std::string& what) {
  for (int f = 0; f < 120; ++f) {
    const Vec3 p = b.camera.at_frame(f, 120).position;
    for (const auto& mesh : b.scene.meshes) {
      if (mesh.name == "floor" || mesh.name == "ceiling" || mesh.name == "walls" || mesh.name == "wire") continue;
      Vec3 lo{1e9f, 1e9f, 1e9f}, hi{-1e9f, -1e9f, -1e9f};
      for (const auto& v : mesh.positions) lo = min(lo, v), hi = max(hi, v);
      const bool inside = p.x > lo.x && p.x < hi.x && p.y > lo.y && p.y < hi.y && p.z > lo.z && p.z < hi.z;
      EXPECT_FALSE(inside) << what << ": frame " << f << " is inside '" << mesh.name << "'";
    }
  }
}

TEST(ProceduralScene, EveryShippedSceneConfigBuildsWithAFreeCameraPath) {
  const fs::path dir = fs::path(CGSR_SOURCE_DIR) / "configs" / "scenes";
  int procedural = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() != ".yaml") continue;
    SCOPED_TRACE(entry.path().string());
    const auto doc = config::Document::load_file(entry.path());
    if (!doc.root()["scene"] || doc.root()["scene"]["type"].as<std::string>() != "procedural") continue;
    ++procedural;
    // The whole file must parse as a render config (unknown keys would fail here).
    const SceneConfig config = config::parse_document(doc, scene_config_schema());
    parse_resolutions(config.resolutions, entry.path().string());
      const SceneBundle b = make_scene(config.scene, 1);
    EXPECT_GT(b.scene.meshes.size(), 3u);
    EXPECT_GE(b.camera.keys.size(), 2u);
    expect_camera_in_free_space(b, entry.path().filename().string());
  }
  EXPECT_GE(procedural, 4);
}

TEST(ProceduralScene, LayoutsProduceTheirCharacteristicGeometry) {
  const auto arena = build("type: procedural\nlayout: arena\nsize: [12, 12]\ntexture_size: 32\n", 3);
  bool has_ceiling = false, has_sun = false;
  for (const auto& m : arena.scene.meshes) has_ceiling |= m.name == "ceiling";
  for (const auto& l : arena.scene.lights) has_sun |= l.type == LightType::Directional;
  EXPECT_FALSE(has_ceiling);
  EXPECT_TRUE(has_sun);
  const auto corridors = build("type: procedural\nlayout: corridors\nsize: [11, 11]\ntexture_size: 32\n", 3);
  expect_camera_in_free_space(corridors, "corridors");
}

TEST(ProceduralTextures, EveryKindTilesSeamlessly) {
  for (const auto& name : texture_kind_names()) {
    SCOPED_TRACE(name);
    const Texture t = make_texture(texture_kind_from_name(name), 64, 7, {0.8f, 0.5f, 0.3f}, {0.1f, 0.2f, 0.3f});
    ASSERT_EQ(t.width, 64);
    ASSERT_EQ(t.data.size(), 64u * 64u * t.channels);
    // Across the wrap-around seam the texture changes no more than between any two neighbouring
    // columns inside it (pattern boundaries may fall on the seam, as they do every few texels).
    auto at = [&](int x, int y, int c) { return static_cast<int>(t.data[(y * 64 + x) * t.channels + c]); };
    auto jump = [&](int x0, int x1) {
      double sum = 0;
      for (int y = 0; y < 64; ++y)
        for (int c = 0; c < 3; ++c) sum += std::abs(at(x1, y, c) - at(x0, y, c));
      return sum;
    };
    double largest_inside = 0;
    for (int x = 0; x < 63; ++x) largest_inside = std::max(largest_inside, jump(x, x + 1));
    EXPECT_LE(jump(63, 0), largest_inside + 64);
  }
  // The noise itself is exactly periodic.
  for (float x : {0.5f, 13.25f, 40.0f})
    EXPECT_FLOAT_EQ(tileable_noise(x, 7.5f, 64, 5, 3), tileable_noise(x + 64, 7.5f + 128, 64, 5, 3));
  const Texture fence = make_texture(TextureKind::ChainLink, 64, 1, {0.7f, 0.7f, 0.7f}, {});
  ASSERT_EQ(fence.channels, 4);
  int holes = 0, wire = 0;
  for (size_t i = 3; i < fence.data.size(); i += 4) (fence.data[i] == 0 ? holes : wire) += 1;
  EXPECT_GT(holes, wire);  // mostly see-through
  EXPECT_GT(wire, 64 * 4);
  EXPECT_THROW(texture_kind_from_name("brick"), Error);
}

}  // namespace
}  // namespace cgsr
