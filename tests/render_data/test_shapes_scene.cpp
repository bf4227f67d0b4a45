// The shapes scene source (SRPO-style training images): the same config gives the same frames,
// the shapes show at every resolution (several colours, object edges, camera motion), the
// shipped config parses, and bad options are errors naming the key.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <filesystem>
#include <set>

#include "core/config.h"
#include "core/error.h"
#include "render_data/procedural/shapes_scene.h"
#include "render_data/render_job.h"
#include "render_data/renderer.h"
#include "render_data/scene_source.h"
#include "test_scenes.h"

namespace cgsr {
namespace {
namespace fs = std::filesystem;

// Small counts and textures: the scene builds and renders in milliseconds.
const std::string kFewShapes =
    "type: shapes\n"
    "counts: {triangles: 3, quads: 2, discs: 2, polygons: 2, rings: 1, bars: 2, curves: 1}\n"
    "size: [0.15, 0.45]\n"
    "thickness: [0.03, 0.06]\n"
    "texture_size: 16\n"
    "camera: {drift: 0.3}\n";
const std::string kSmall = kFewShapes + "textured: 0.3\n";

using test::build_scene;

std::string error_of(const std::string& yaml) {
  try {
    build_scene(yaml, 1);
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for:\n" << yaml;
  return "";
}

// Frame `frame` of 8 at width x height, with motion from frame - 1.
GBuffer render(const SceneBundle& b, int frame, int width, int height) {
  const SceneRenderer renderer(b.scene, test::unshadowed());
  return renderer.render(b.camera.at_frame(frame, 8), b.camera.at_frame(frame - 1, 8), width, height,
                         b.camera.near_plane, b.camera.far_plane);
}

bool same_positions(const SceneBundle& a, const SceneBundle& b) {
  if (a.scene.meshes.size() != b.scene.meshes.size()) return false;
  for (size_t m = 0; m < a.scene.meshes.size(); ++m) {
    const auto &pa = a.scene.meshes[m].positions, &pb = b.scene.meshes[m].positions;
    if (pa.size() != pb.size()) return false;
    for (size_t v = 0; v < pa.size(); ++v)
      if (pa[v].x != pb[v].x || pa[v].y != pb[v].y || pa[v].z != pb[v].z) return false;
  }
  return true;
}

TEST(ShapesScene, SameConfigAndSeedGiveTheSameFramesOtherSeedsOrVariantsOthers) {
  const auto a = build_scene(kSmall, 5), b = build_scene(kSmall, 5);
  EXPECT_TRUE(same_positions(a, b));
  EXPECT_FALSE(same_positions(a, build_scene(kSmall, 6)));
  EXPECT_FALSE(same_positions(a, build_scene(kSmall + "variant: 1\n", 5)));
  const auto fa = render(a, 3, 64, 48), fb = render(b, 3, 64, 48);
  EXPECT_TRUE(torch::equal(fa.color, fb.color));
  EXPECT_TRUE(torch::equal(fa.edge, fb.edge));
  EXPECT_TRUE(torch::equal(fa.motion, fb.motion));
}

TEST(ShapesScene, ShapesShowAtEveryResolutionWithEdgesAndMotion) {
  const auto bundle = build_scene(kSmall, 7);
  EXPECT_EQ(bundle.scene.meshes.size(), 14u);  // the background and 13 shapes, one object each
  for (const auto& [w, h] : {std::pair{64, 48}, std::pair{128, 96}}) {
    SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h));
    const GBuffer g = render(bundle, 4, w, h);
    // Every pixel is geometry (the background plane covers the view).
    EXPECT_TRUE(torch::isfinite(g.depth).all().item<bool>());
    // Several objects and colours are visible.
    const auto ids = std::get<0>(torch::_unique(g.object_id.flatten()));
    EXPECT_GE(ids.numel(), 5);
    const auto quantized = (g.color * 255).round().to(torch::kInt64);
    const auto key = (quantized[0] * 256 + quantized[1]) * 256 + quantized[2];
    EXPECT_GE(std::get<0>(torch::_unique(key.flatten())).numel(), 5);
    // Shape outlines are edges; most of the image is not.
    const double edge_share = g.edge.mean().item<double>();
    EXPECT_GT(edge_share, 0.01);
    EXPECT_LT(edge_share, 0.5);
    // Shapes lie at different depths in front of the background.
    const auto depths = std::get<0>(torch::_unique(g.depth.flatten()));
    EXPECT_GE(depths.numel(), 3);
    // The camera drifts: motion is small but not zero.
    const double moving = (g.motion.abs().sum(0) > 1e-3).to(torch::kFloat32).mean().item<double>();
    EXPECT_GT(moving, 0.5);
    EXPECT_LT(g.motion.abs().max().item<double>(), 0.1 * w);
  }
}

TEST(ShapesScene, FlatShapesRenderAsExactColoursWithoutBlending) {
  // No gradients or textures: every pixel is the background's or one shape's exact colour.
  const auto bundle = build_scene(kFewShapes + "gradients: 0\ntextured: 0\n", 9);
  const GBuffer g = render(bundle, 0, 128, 96);
  const auto quantized = (g.color * 255).round().to(torch::kInt64);
  const auto key = ((quantized[0] * 256 + quantized[1]) * 256 + quantized[2]).flatten();
  const auto ids = g.object_id.flatten().to(torch::kInt64);
  // Each visible object has exactly one colour.
  const auto pairs = std::get<0>(torch::_unique(ids * int64_t{1 << 24} + key));
  EXPECT_EQ(pairs.numel(), std::get<0>(torch::_unique(ids)).numel());
}

TEST(ShapesScene, TheShippedConfigParsesAsARenderConfig) {
  const auto doc = config::Document::load_file(fs::path(CGSR_SOURCE_DIR) / "configs" / "scenes" / "shapes.yaml");
  const test::SceneConfig job = config::parse_document(doc, test::scene_config_schema());  // unknown keys would fail
  const auto resolutions = parse_resolutions(job.resolutions, "shapes.yaml");
  EXPECT_EQ(resolutions.size(), 2u);
  const auto bundle = make_scene(job.scene, 1);
  EXPECT_GT(bundle.scene.meshes.size(), 30u);
  EXPECT_GE(bundle.camera.keys.size(), 2u);
}

TEST(ShapesScene, BadOptionsAreErrorsNamingTheKey) {
  struct Case {
    std::string yaml, expected;
  } cases[] = {
      {"type: shapes\nsizes: [0.1, 0.2]\n", "did you mean 'size'"},
      {"type: shapes\nsize: [0.4, 0.1]\n", "lo <= hi"},
      {"type: shapes\nsize: [0.1]\n", "lo <= hi"},
      {"type: shapes\nthickness: [0, 0.1]\n", "thickness"},
      {"type: shapes\ncounts: {triangles: -1}\n", "counts.triangles"},
      {"type: shapes\ncounts: {triangles: 0, quads: 0, discs: 0, polygons: 0, rings: 0, bars: 0, curves: 0}\n",
       "needs at least one shape"},
      {"type: shapes\ncounts: {squares: 3}\n", "unknown key 'squares'"},
      {"type: shapes\ndepth_range: 0.9\n", "depth_range"},
      {"type: shapes\ngradients: 1.5\n", "gradients"},
      {"type: shapes\ncamera: {keys: 1}\n", "camera.keys"},
      {"type: shapes\ncamera: {vfov: 170}\n", "camera.vfov"},
  };
  for (const auto& c : cases) {
    const std::string what = error_of(c.yaml);
    EXPECT_NE(what.find(c.expected), std::string::npos) << c.yaml << " -> " << what;
    EXPECT_NE(what.find("test.yaml"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace cgsr
