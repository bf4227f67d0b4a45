// The procedural scene source: determinism, every shipped scene config, a camera that never
// passes through geometry, tileable textures, and variety drawn from the seed.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>

#include "core/config.h"
#include "core/error.h"
#include "core/text.h"
#include "render_data/procedural/procedural_scene.h"
#include "render_data/procedural/procedural_textures.h"
#include "render_data/procedural/procedural_variety.h"
#include "test_scenes.h"
#include "render_data/render_job.h"
#include "render_data/scene_source.h"

namespace cgsr {
namespace {
namespace fs = std::filesystem;

using test::build_scene;
using test::SceneConfig;
using test::scene_config_schema;

TEST(ProceduralScene, SameSeedSameSceneOtherSeedOtherScene) {
  const std::string yaml = "type: procedural\nlayout: room\nsize: [12, 10]\ntexture_size: 32\n";
  const auto a = build_scene(yaml, 5), b = build_scene(yaml, 5), c = build_scene(yaml, 6);
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
    build_scene("type: procedural\nlayuot: room\n", 1);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("test.yaml:2"), std::string::npos) << what;
    EXPECT_NE(what.find("did you mean 'layout'"), std::string::npos) << what;
  }
}

TEST(ProceduralScene, TooManyPropsForTheRoomIsAnError) {
  EXPECT_THROW(build_scene("type: procedural\nsize: [4, 4]\nprops: {crates: 40}\n", 1), Error);
}

// The camera must not be inside any prop or wall: check every mesh's bounding box (shrunk a
// little, boxes of thin things are fine to touch) against camera positions along the path.
void expect_camera_in_free_space(const SceneBundle& b, const std::string& what) {
  for (int f = 0; f < 120; ++f) {
    const Vec3 p = b.camera.at_frame(f, 120).position;
    for (const auto& mesh : b.scene.meshes) {
      // Walls, floor, ceiling: the walk avoids wall cells; cables hang overhead; the skyline stands
      // outside the level (one mesh around it).
      if (mesh.name == "floor" || mesh.name == "ceiling" || mesh.name == "walls" || mesh.name == "wire" ||
          mesh.name == "skyline")
        continue;
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
  const auto arena = build_scene("type: procedural\nlayout: arena\nsize: [12, 12]\ntexture_size: 32\n", 3);
  bool has_ceiling = false, has_sun = false;
  for (const auto& m : arena.scene.meshes) has_ceiling |= m.name == "ceiling";
  for (const auto& l : arena.scene.lights) has_sun |= l.type == LightType::Directional;
  EXPECT_FALSE(has_ceiling);
  EXPECT_TRUE(has_sun);
  const auto corridors = build_scene("type: procedural\nlayout: corridors\nsize: [11, 11]\ntexture_size: 32\n", 3);
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

// ---- variety ----------------------------------------------------------------------------------

const std::string kVariety = "type: procedural\nlayout: random\ntexture_size: 32\nvariety: {size: [7, 10]}\n";

// Everything a renderer reads from a scene, compared exactly.
void expect_identical(const SceneBundle& a, const SceneBundle& b) {
  ASSERT_EQ(a.scene.meshes.size(), b.scene.meshes.size());
  for (size_t m = 0; m < a.scene.meshes.size(); ++m) {
    const Mesh &x = a.scene.meshes[m], &y = b.scene.meshes[m];
    ASSERT_EQ(x.positions.size(), y.positions.size()) << x.name;
    EXPECT_EQ(0, std::memcmp(x.positions.data(), y.positions.data(), x.positions.size() * sizeof(Vec3))) << x.name;
    EXPECT_EQ(x.indices, y.indices);
    EXPECT_EQ(x.material, y.material);
  }
  ASSERT_EQ(a.scene.textures.size(), b.scene.textures.size());
  for (size_t t = 0; t < a.scene.textures.size(); ++t) EXPECT_EQ(a.scene.textures[t].data, b.scene.textures[t].data);
  ASSERT_EQ(a.scene.lights.size(), b.scene.lights.size());
  for (size_t l = 0; l < a.scene.lights.size(); ++l) EXPECT_EQ(a.scene.lights[l].color.x, b.scene.lights[l].color.x);
  EXPECT_EQ(a.scene.fog.density, b.scene.fog.density);
  EXPECT_EQ(a.scene.sky.zenith.z, b.scene.sky.zenith.z);
  ASSERT_EQ(a.camera.keys.size(), b.camera.keys.size());
  for (size_t k = 0; k < a.camera.keys.size(); ++k) EXPECT_EQ(a.camera.keys[k].pose.yaw, b.camera.keys[k].pose.yaw);
}

// The texture family of every material ("bricks3" -> "bricks").
std::set<std::string> families(const Scene& scene) {
  std::set<std::string> out;
  for (const auto& m : scene.materials)
    if (m.albedo_texture >= 0) out.insert(m.name.substr(0, m.name.find_first_of("0123456789")));
  return out;
}

TEST(ProceduralVariety, SameSeedSameLevelOtherSeedsOtherLevels) {
  expect_identical(build_scene(kVariety, 11), build_scene(kVariety, 11));
  expect_identical(build_scene(kVariety + "variant: 4\n", 11), build_scene(kVariety + "variant: 4\n", 11));
  // Over 40 seeds every layout, dark and bright, fog on and off; over a dozen, many texture families.
  ProceduralOptions options;
  options.layout = ProceduralLayout::Random;
  options.variety.enabled = true;
  std::set<std::string> layouts, all_families;
  float darkest = 1e9f, brightest = 0;
  int foggy = 0;
  for (uint64_t seed = 1; seed <= 40; ++seed) {
    const ProceduralOptions drawn = draw_variety(options, seed);
    layouts.insert(enum_name(drawn.layout));
    darkest = std::min(darkest, drawn.lighting.ambient);
    brightest = std::max(brightest, drawn.lighting.ambient);
    foggy += drawn.fog.density > 0;
    if (seed <= 12)
      for (const auto& f : families(build_scene(kVariety, seed).scene)) all_families.insert(f);
  }
  EXPECT_EQ(layouts.size(), 5u) << join(std::vector<std::string>(layouts.begin(), layouts.end()));
  EXPECT_GE(all_families.size(), 8u) << join(std::vector<std::string>(all_families.begin(), all_families.end()));
  EXPECT_GT(brightest, 3 * darkest);
  EXPECT_GT(foggy, 0);
  EXPECT_LT(foggy, 40);
  // A variant is another level of the same seed; variant 0 is the seed's own level.
  const auto base = build_scene(kVariety, 11), other = build_scene(kVariety + "variant: 1\n", 11);
  EXPECT_TRUE(base.scene.meshes.size() != other.scene.meshes.size() ||
              base.scene.textures[0].data != other.scene.textures[0].data);
  expect_identical(base, build_scene(kVariety + "variant: 0\n", 11));
}

TEST(ProceduralVariety, SameSeedRendersBitIdenticalFrames) {
  const fs::path root = test::scratch_dir("variety_frames");
  std::vector<std::string> colour;
  for (const char* run : {"a", "b"}) {
    RenderJobOptions job;
    job.frames = 2;
    job.resolutions = {"32x24", "64x48"};
    job.shadow_map_size = 64;
    const auto doc = config::Document::parse(kVariety, "variety.yaml");
    job.scene = config::Block{doc.root(), std::make_shared<config::Document>(doc), "scene"};
    run_render_job(job, 3, root / run);
    std::ifstream in(root / run / "64x48" / "color" / "000001.png", std::ios::binary);
    colour.emplace_back(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  ASSERT_GT(colour[0].size(), 100u);
  EXPECT_EQ(colour[0], colour[1]);
}

TEST(ProceduralVariety, EveryLayoutHasAWalkableCameraPath) {
  for (const std::string layout : {"room", "corridors", "hall", "arena", "outdoor"})
    for (uint64_t seed : {1, 2, 3}) {
      SCOPED_TRACE(layout + " seed " + std::to_string(seed));
      const auto b = build_scene("type: procedural\nlayout: " + layout + "\ntexture_size: 32\nvariety: {size: [6, 12]}\n", seed);
      ASSERT_GE(b.camera.keys.size(), 2u);
      EXPECT_GT(length(b.camera.keys.back().pose.position - b.camera.keys.front().pose.position) +
                    length(b.camera.keys[1].pose.position - b.camera.keys[0].pose.position),
                0.5f);
      expect_camera_in_free_space(b, layout);
      bool ceiling = false, columns = false, skyline = false;
      for (const auto& m : b.scene.meshes) {
        ceiling |= m.name == "ceiling";
        columns |= m.name == "column";
        skyline |= m.name == "skyline";
      }
      EXPECT_EQ(ceiling, layout != "arena" && layout != "outdoor");
      EXPECT_EQ(skyline, layout == "outdoor");
      if (layout == "hall") {
        EXPECT_TRUE(columns);
      }
    }
  // Without variety, the new layouts build too (fixed materials).
  expect_camera_in_free_space(build_scene("type: procedural\nlayout: hall\nsize: [10, 9]\nheight: 8\ntexture_size: 32\n", 2), "hall");
  expect_camera_in_free_space(build_scene("type: procedural\nlayout: outdoor\nsize: [10, 9]\ntexture_size: 32\n", 2), "outdoor");
}

TEST(ProceduralVariety, BadRangesAreErrorsNamingTheKey) {
  auto message = [](const std::string& variety) {
    try {
      build_scene("type: procedural\nlayout: random\nvariety: " + variety + "\n", 1);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("{size: [12, 6]}").find("variety.size: must be [lo, hi] with lo <= hi"), std::string::npos)
      << message("{size: [12, 6]}");
  EXPECT_NE(message("{size: [2, 6]}").find("variety.size[0]: '2' is out of range [5, 60]"), std::string::npos);
  EXPECT_NE(message("{materials: [grate]}").find("needs at least one family without holes"), std::string::npos);
  EXPECT_NE(message("{materials: [brick]}").find("did you mean 'bricks'"), std::string::npos);
  EXPECT_NE(message("{layouts: []}").find("needs at least one layout"), std::string::npos);
  EXPECT_NE(message("{layouts: [maze]}").find("one of: room, corridors, hall, arena, outdoor"), std::string::npos);
  EXPECT_NE(message("{layouts: [rooms]}").find("did you mean 'room'"), std::string::npos);
  EXPECT_NE(message("{layouts: [room, random]}").find("variety.layouts: random draws from this list"), std::string::npos)
      << message("{layouts: [room, random]}");
  EXPECT_NE(message("{brightness: [0, 2]}").find("variety.brightness"), std::string::npos);
  EXPECT_NE(message("{fog: 2}").find("variety.fog"), std::string::npos);
}

}  // namespace
}  // namespace cgsr
