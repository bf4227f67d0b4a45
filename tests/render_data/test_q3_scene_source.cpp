// The q3bsp scene source end to end on the tiny pk3: loader statistics, the registry, the axis
// conversion, and rendered colours (lightmapped floor and patch, vertex-lit mesh, sky) checked
// against the game's formula.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <fstream>

#include "core/color.h"
#include "core/error.h"
#include "render_data/camera.h"
#include "render_data/q3/q3_scene_source.h"
#include "render_data/renderer.h"
#include "render_data/scene_source.h"
#include "tests/render_data/q3_test_map.h"
#include "tests/support/cli_runner.h"

namespace cgsr::q3 {
namespace {

class Q3SceneSource : public ::testing::Test {
 protected:
  void SetUp() override {
    map_ = testing::make_test_map();
    pk3_ = dir_.path() / "tiny.pk3";
    testing::write_pk3(pk3_, testing::test_map_files(map_));
  }
  Q3SceneOptions options() const {
    Q3SceneOptions o;
    o.map = "tiny";
    o.data_root = "";
    o.pk3 = {pk3_.string()};
    o.camera.length = 800;
    return o;
  }
  testing::TempDir dir_;
  testing::TestMap map_;
  std::filesystem::path pk3_;
};

// Display colour of the game's formula: texture x light x 2^overbright in display space, as the
// scene computes it in linear light.
float game_colour(uint8_t texel, uint8_t light, float linear_factor) {
  const auto t = srgb_to_linear(torch::full({1}, texel / 255.0f)), l = srgb_to_linear(torch::full({1}, light / 255.0f));
  return linear_to_srgb(t * l * linear_factor).item<float>();
}

// Looks from a Quake-space point with a Quake yaw and pitch; renders w x h.
GBuffer look(const SceneRenderer& renderer, const SceneBundle& b, Vec3 quake_eye, float yaw, float pitch,
             float unit_scale) {
  QuakeCameraKey key;
  key.position = quake_eye;
  key.yaw = yaw;
  key.pitch = pitch;
  const CameraPose pose = quake_to_scene_pose(key, unit_scale, 60);
  return renderer.render(pose, pose, 32, 24, b.camera.near_plane, b.camera.far_plane);
}

Vec3 centre_colour(const GBuffer& g) {
  const auto c = g.color.index({torch::indexing::Slice(), 12, 16});
  return {c[0].item<float>(), c[1].item<float>(), c[2].item<float>()};
}
const Material& centre_material(const GBuffer& g, const Scene& s) {
  const int id = g.material_id.index({0, 12, 16}).item<int>();
  EXPECT_GE(id, 0);
  return s.materials.at(std::max(id, 0));
}

TEST_F(Q3SceneSource, LoadsEveryFaceKindAndCountsSkippedSurfaces) {
  Q3SceneReport report;
  const SceneBundle b = load_q3_scene(options(), 1, &report);
  const Q3LevelStats& s = report.level;
  EXPECT_EQ(report.archives, 1u);
  EXPECT_EQ(report.bsp, "tiny.pk3:maps/tiny.bsp");
  EXPECT_EQ(s.faces, static_cast<int>(map_.bsp.faces.size()));
  EXPECT_EQ(s.polygons, 7);  // floor, sky, four walls, grate
  EXPECT_EQ(s.patches, 1);
  EXPECT_EQ(s.meshes, 1);
  EXPECT_EQ(s.sky_faces, 1);
  EXPECT_EQ(s.skipped_billboards, 1);
  EXPECT_EQ(s.skipped_invisible, 1);  // caulk
  EXPECT_EQ(s.skipped_transparent, 1);  // glass
  EXPECT_EQ(s.alpha_tested_faces, 1);
  EXPECT_EQ(s.vertex_lit_faces, 1);
  EXPECT_EQ(s.patch_triangles, 8 * 8 * 2);
  EXPECT_EQ(s.triangles, 7 * 2 + 8 * 8 * 2 + 3);
  EXPECT_TRUE(s.missing_images.empty());
  EXPECT_EQ(static_cast<int>(triangle_count(b.scene)), s.triangles);
  validate_scene(b.scene);
  validate_camera_path(b.camera, "tiny");
  EXPECT_EQ(b.scene.name, "tiny");
  // The grate keeps its alpha for the cut-out; its texture is RGBA.
  bool grate = false;
  for (const auto& m : b.scene.materials)
    if (m.name.rfind("textures/test/grate", 0) == 0) {
      grate = true;
      EXPECT_FLOAT_EQ(m.alpha_cutoff, 0.5f);
      EXPECT_EQ(b.scene.textures.at(m.albedo_texture).channels, 4);
      EXPECT_TRUE(m.two_sided);
    }
  EXPECT_TRUE(grate);
  // Sky colours come from the sky shader's constant colour.
  const auto zenith = srgb_to_linear(torch::tensor({0.2f, 0.4f, 0.8f}));
  EXPECT_NEAR(b.scene.sky.zenith.z, zenith[2].item<float>(), 1e-4);
  // Camera keys: metres, eye height above the floor.
  EXPECT_NEAR(b.camera.keys.front().pose.position.y, 50.125f / 32, 1e-3);
  EXPECT_NEAR(b.camera.near_plane, 4.0f / 32, 1e-6);
  EXPECT_NEAR(report.path.length, 800, 1);
}

TEST_F(Q3SceneSource, QuakeAxesBecomeTheScenesAxes) {
  EXPECT_TRUE(testing::same(quake_to_scene({1, 2, 3}, 1), Vec3{1, 3, -2}));
  EXPECT_TRUE(testing::same(quake_to_scene({32, 0, 0}, 1.0f / 32), Vec3{1, 0, 0}));
  // Quake yaw 0 looks along +x, yaw 90 along +y; pitch is positive up.
  for (const auto& [yaw, quake_dir] : {std::pair{0.0f, Vec3{1, 0, 0}}, {90.0f, Vec3{0, 1, 0}}, {180.0f, Vec3{-1, 0, 0}}}) {
    QuakeCameraKey key;
    key.yaw = yaw;
    const FrameCamera cam = make_frame_camera(quake_to_scene_pose(key, 1, 60), 8, 8, 0.1f, 10);
    const Vec3 expected = quake_to_scene(quake_dir, 1);
    EXPECT_NEAR(cam.forward.x, expected.x, 1e-5);
    EXPECT_NEAR(cam.forward.z, expected.z, 1e-5);
  }
  QuakeCameraKey up;
  up.pitch = 30;
  EXPECT_NEAR(make_frame_camera(quake_to_scene_pose(up, 1, 60), 8, 8, 0.1f, 10).forward.y, 0.5f, 1e-5);
}

TEST_F(Q3SceneSource, RendersTheGamesColours) {
  const auto o = options();
  const SceneBundle b = load_q3_scene(o, 1);
  const SceneRenderer renderer(b.scene, RenderSettings{});
  const float scale = static_cast<float>(o.unit_scale), k = overbright_factor(o.overbright_bits);
  const auto lm = shift_lighting(map_.lightmap_texel.data(), o.map_overbright_bits - o.overbright_bits);
  EXPECT_EQ(lm, (std::array<uint8_t, 3>{200, 160, 120}));

  // Floor, looking straight down: floor texel x shifted lightmap x overbright.
  const GBuffer floor = look(renderer, b, {-100, -100, 100}, 0, -89, scale);
  EXPECT_EQ(centre_material(floor, b.scene).name, "textures/test/floor#lm0");
  const Vec3 f = centre_colour(floor);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(f[c], game_colour(map_.floor_texel[c], lm[c], k), 0.01) << c;
  EXPECT_NEAR(floor.depth.index({0, 12, 16}).item<float>(), 100 * scale, 0.01);
  EXPECT_NEAR(floor.normal.index({2, 12, 16}).item<float>(), 1.0f, 0.01);  // view space: facing the camera

  // The vertex-lit pyramid: white texture x shifted vertex colour x overbright.
  const GBuffer pyramid = look(renderer, b, {128, 128, 120}, 0, -89, scale);
  EXPECT_EQ(centre_material(pyramid, b.scene).name, "textures/test/mesh#vertex");
  const auto vc = shift_lighting(map_.mesh_vertex_color.data(), 1);
  EXPECT_EQ(vc, (std::array<uint8_t, 3>{255, 127, 63}));
  const Vec3 p = centre_colour(pyramid);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(p[c], game_colour(255, vc[c], k), 0.01) << c;

  // The patch (quarter pipe on the -x wall), looking at it.
  const GBuffer pipe = look(renderer, b, {-150, 0, 40}, 180, -15, scale);
  EXPECT_EQ(centre_material(pipe, b.scene).name, "textures/test/patch#lm0");
  const Vec3 q = centre_colour(pipe);
  const uint8_t patch_texel[3] = {120, 200, 120};
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(q[c], game_colour(patch_texel[c], lm[c], k), 0.01) << c;

  // The sky ceiling: the sky shader's constant colour at the zenith.
  const GBuffer sky = look(renderer, b, {0, 0, 128}, 0, 89, scale);
  EXPECT_EQ(sky.material_id.index({0, 12, 16}).item<int>(), -1);  // the G-buffer's "sky"
  const Vec3 s = centre_colour(sky);
  EXPECT_NEAR(s.x, 0.2f, 0.01);
  EXPECT_NEAR(s.y, 0.4f, 0.01);
  EXPECT_NEAR(s.z, 0.8f, 0.01);
  EXPECT_TRUE(std::isinf(sky.depth.index({0, 12, 16}).item<float>()));
}

TEST_F(Q3SceneSource, TheRegistryBuildsItFromAConfigBlock) {
  ASSERT_TRUE(scene_sources().contains("q3bsp"));
  const auto doc = std::make_shared<config::Document>(config::Document::parse(
      "scene:\n  type: q3bsp\n  map: tiny\n  data_root: ''\n  pk3: ['" + pk3_.string() +
          "']\n  patch_level: 4\n  camera: {length: 400, vfov: 70}\n",
      "test.yaml"));
  const config::Block block{doc->root()["scene"], doc, "scene"};
  const SceneBundle b = make_scene(block, 5);
  EXPECT_EQ(b.scene.name, "tiny");
  EXPECT_FLOAT_EQ(b.camera.keys.front().pose.vfov, 70);
  // The first frame of the path sees the room.
  const SceneRenderer renderer(b.scene, RenderSettings{});
  const GBuffer g = renderer.render(b.camera.at_frame(0, 10), b.camera.at_frame(0, 10), 32, 24, b.camera.near_plane,
                                    b.camera.far_plane);
  EXPECT_GT((g.material_id >= 0).sum().item<int64_t>(), 32 * 24 / 2);
  EXPECT_TRUE(torch::isfinite(g.color).all().item<bool>());

  const auto typo = std::make_shared<config::Document>(
      config::Document::parse("scene: {type: q3bsp, map: tiny, patch_levl: 3}\n", "typo.yaml"));
  try {
    make_scene({typo->root()["scene"], typo, "scene"}, 1);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("patch_level"), std::string::npos) << e.what();
  }
}

TEST_F(Q3SceneSource, MissingGameDataNamesThePackagesAndTheInstallCommand) {
  auto o = options();
  o.data_root = (dir_.path() / "no_openarena_here").string();
  o.pk3.clear();
  try {
    load_q3_scene(o, 1);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("openarena-088-data"), std::string::npos) << m;
    EXPECT_NE(m.find("sudo apt-get install openarena-088-data openarena-data"), std::string::npos) << m;
  }
  auto unknown = options();
  unknown.map = "tinx";
  try {
    load_q3_scene(unknown, 1);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("maps/tinx.bsp"), std::string::npos) << m;
    EXPECT_NE(m.find("did you mean 'tiny'"), std::string::npos) << m;
  }
}

TEST_F(Q3SceneSource, CgsrRenderWritesADatasetFromAQ3Config) {
  const auto config = dir_.path() / "tiny_q3.yaml";
  std::ofstream(config) << "name: tiny_q3\nframes: 3\nresolutions: [64x48, 128x96]\nshadows: false\n"
                           "scene:\n  type: q3bsp\n  map: tiny\n  data_root: ''\n  pk3: ['"
                        << pk3_.string() << "']\n  camera: {length: 200}\n";
  const auto out = dir_.path() / "dataset";
  const auto r = cgsr::test::run_cgsr("render --config " + config.string() + " --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(std::filesystem::exists(out / "128x96" / "color" / "000002.png"));
  EXPECT_TRUE(std::filesystem::exists(out / "64x48" / "depth" / "000000.exr"));
  const std::string manifest = cgsr::test::slurp(out / "manifest.yaml");
  EXPECT_NE(manifest.find("scene_source: q3bsp"), std::string::npos) << manifest;
}

// Every OpenArena scene config, pointed at a directory without the game: the error names the
// packages and the command that installs them (whether or not this machine has them).
TEST(Q3SceneConfigs, RenderWithoutTheGameDataSaysWhatToInstall) {
  const auto configs = std::filesystem::path(CGSR_SOURCE_DIR) / "configs" / "scenes";
  testing::TempDir dir;
  int checked = 0;
  for (const auto& entry : std::filesystem::directory_iterator(configs)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("oa_", 0) != 0) continue;
    const auto r = cgsr::test::run_cgsr("render --config " + entry.path().string() + " --set scene.data_root=" +
                                        (dir.path() / "no_game").string() + " --out " +
                                        (dir.path() / name).string());
    EXPECT_EQ(r.exit_code, 2) << name << ": " << r.err;
    EXPECT_NE(r.err.find("openarena-088-data openarena-data"), std::string::npos) << name << ": " << r.err;
    EXPECT_NE(r.err.find("sudo apt-get install openarena-088-data openarena-data"), std::string::npos) << r.err;
    ++checked;
  }
  EXPECT_GE(checked, 2);
}

}  // namespace
}  // namespace cgsr::q3
