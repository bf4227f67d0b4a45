// Sub-pixel jitter of the low-resolution frames: the Halton sequence, a jittered render against
// the unjittered camera it is offset from, motion vectors that exclude the jitter, and the
// offsets through the data set (manifest, loader).
#include <gtest/gtest.h>

#include <torch/torch.h>

#include <cmath>
#include <fstream>
#include <set>
#include <utility>

#include "core/error.h"
#include "render_data/camera.h"
#include "render_data/dataset.h"
#include "render_data/dataset_manifest.h"
#include "render_data/frame.h"
#include "render_data/jitter.h"
#include "render_data/render_job.h"
#include "render_data/renderer.h"
#include "render_data/scene_source.h"
#include "test_scenes.h"

namespace cgsr {
namespace {
namespace fs = std::filesystem;

JitterSettings halton_jitter(int phases) {
  JitterSettings j;
  j.sequence = "halton";
  j.phases = phases;
  return j;
}

TEST(Jitter, HaltonFirstValuesAreTheRadicalInverses) {
  const double base2[] = {1 / 2.0, 1 / 4.0, 3 / 4.0, 1 / 8.0, 5 / 8.0, 3 / 8.0, 7 / 8.0, 1 / 16.0};
  const double base3[] = {1 / 3.0, 2 / 3.0, 1 / 9.0, 4 / 9.0, 7 / 9.0, 2 / 9.0, 5 / 9.0, 8 / 9.0, 1 / 27.0};
  for (int i = 0; i < 8; ++i) EXPECT_DOUBLE_EQ(halton(i + 1, 2), base2[i]) << "index " << i + 1;
  for (int i = 0; i < 9; ++i) EXPECT_DOUBLE_EQ(halton(i + 1, 3), base3[i]) << "index " << i + 1;
}

TEST(Jitter, OffsetsAreHaltonLessAHalfAndWrapAtThePhases) {
  const JitterSettings j8 = halton_jitter(8);
  // Frame 0 is Halton point 1: (1/2, 1/3) - 0.5.
  EXPECT_FLOAT_EQ(jitter_offset(j8, 0).x, 0.0f);
  EXPECT_FLOAT_EQ(jitter_offset(j8, 0).y, static_cast<float>(1 / 3.0 - 0.5));
  EXPECT_FLOAT_EQ(jitter_offset(j8, 1).x, -0.25f);
  EXPECT_FLOAT_EQ(jitter_offset(j8, 1).y, static_cast<float>(2 / 3.0 - 0.5));
  EXPECT_FLOAT_EQ(jitter_offset(j8, 2).x, 0.25f);
  EXPECT_FLOAT_EQ(jitter_offset(j8, 2).y, static_cast<float>(1 / 9.0 - 0.5));
  std::set<std::pair<float, float>> distinct;
  for (int f = 0; f < 8; ++f) {
    const Vec2 o = jitter_offset(j8, f);
    EXPECT_GE(o.x, -0.5f);
    EXPECT_LT(o.x, 0.5f);
    EXPECT_GE(o.y, -0.5f);
    EXPECT_LT(o.y, 0.5f);
    distinct.insert({o.x, o.y});
    for (int k = 1; k < 4; ++k) {  // the phase is the frame mod 8
      EXPECT_EQ(jitter_offset(j8, f + 8 * k).x, o.x);
      EXPECT_EQ(jitter_offset(j8, f + 8 * k).y, o.y);
    }
  }
  EXPECT_EQ(distinct.size(), 8u);
  // 16 phases: the first 8 are the same points, then 8 more before the wrap.
  const JitterSettings j16 = halton_jitter(16);
  EXPECT_EQ(jitter_offset(j16, 5).x, jitter_offset(j8, 5).x);
  EXPECT_NE(jitter_offset(j16, 8).y, jitter_offset(j8, 8).y);
  EXPECT_EQ(jitter_offset(j16, 16).y, jitter_offset(j16, 0).y);
  const Vec2 off = jitter_offset(JitterSettings{}, 3);
  EXPECT_EQ(off.x, 0.0f);
  EXPECT_EQ(off.y, 0.0f);
}

// Every pixel centre c of a jittered render sees what the unjittered camera sees at c - offset:
// the depth of a floor (which varies across the image) against the ray-plane intersection.
TEST(Jitter, AJitteredRenderIsTheUnjitteredViewOffsetByTheJitter) {
  Scene s = test::empty_scene();
  test::add_quad(s, {0, -1, -500}, {500, 0, 0}, {0, 0, -500}, 1);  // floor y = -1, z in [-1000, 0]
  SceneRenderer r(s, test::unshadowed());
  CameraPose pose;
  pose.pitch = -20;
  const int W = 40, H = 30;
  const Vec2 jitter{0.3f, -0.4f};
  const GBuffer g = r.render(pose, pose, W, H, 0.1f, 200.0f, jitter);
  const GBuffer plain = r.render(pose, pose, W, H, 0.1f, 200.0f);
  const FrameCamera cam = make_frame_camera(pose, W, H, 0.1f, 200.0f);
  auto d = g.depth.accessor<float, 3>();
  int floor_pixels = 0;
  for (int i = 0; i < H; ++i)
    for (int j = 0; j < W; ++j) {
      const Vec3 ray = pixel_ray(cam, j + 0.5f - jitter.x, i + 0.5f - jitter.y);
      if (ray.y >= -1e-3f) continue;  // at or above the horizon: sky or a grazing floor
      const float expected = -1.0f / ray.y;  // view depth: the ray's forward component is 1
      if (expected > 150.0f) continue;
      ++floor_pixels;
      EXPECT_NEAR(d[0][i][j], expected, 1e-4f * expected) << i << "," << j;
    }
  EXPECT_GT(floor_pixels, W * H / 3);
  // The offset is visible: the floor's depth moved against the unjittered render.
  EXPECT_GT((g.depth - plain.depth).abs().nan_to_num(0, 0, 0).max().item<float>(), 1e-3f);
}

// Motion excludes the jitter (the FSR 2 convention): a still camera over a static scene has no
// motion, whatever the offset of either frame; a moving camera the motion of the unjittered one.
TEST(Jitter, MotionExcludesTheJitter) {
  Scene s = test::empty_scene();
  test::add_quad(s, {0.5f, 0, -4}, {1, 0, 0}, {0, 1, 0}, 1);  // a card, the sky around it
  SceneRenderer r(s, test::unshadowed());
  CameraPose pose;
  const int W = 32, H = 24;
  const JitterSettings j8 = halton_jitter(8);
  for (int f = 0; f < 8; ++f) {
    const GBuffer g = r.render(pose, pose, W, H, 0.1f, 100.0f, jitter_offset(j8, f));
    EXPECT_LT(g.motion.abs().max().item<float>(), 1e-4f) << "phase " << f;
    EXPECT_EQ(g.motion_rejected, 0);
  }
  CameraPose now = pose;
  now.position = {0.3f, -0.1f, 0};
  Scene w = test::empty_scene();
  test::add_quad(w, {0, 0, -4}, {50, 0, 0}, {0, 50, 0}, 2);  // every pixel a surface at depth 4
  SceneRenderer wall(w, test::unshadowed());
  const GBuffer g = wall.render(now, pose, W, H, 0.1f, 100.0f, {0.37f, -0.21f});
  const FrameCamera cam = make_frame_camera(now, W, H, 0.1f, 100.0f);
  const float mx = cam.focal_px * 0.3f / 4.0f, my = cam.focal_px * 0.1f / 4.0f;
  auto d = g.depth.accessor<float, 3>();
  auto m = g.motion.accessor<float, 3>();
  for (int i = 0; i < H; ++i)
    for (int j = 0; j < W; ++j) {
      ASSERT_NEAR(d[0][i][j], 4.0f, 1e-3f);
      EXPECT_NEAR(m[0][i][j], mx, 1e-3f) << i << "," << j;
      EXPECT_NEAR(m[1][i][j], my, 1e-3f) << i << "," << j;
    }
}

TEST(Jitter, OffsetsRoundTripThroughTheManifest) {
  const fs::path dir = test::scratch_dir("jitter_manifest");
  DatasetManifest m;
  m.name = "j";
  m.fingerprint = "0123456789abcdef";
  m.frames = 20;
  m.resolutions = {{32, 24}, {64, 48}};
  m.split = make_split(20);
  m.jitter_sequence = "halton";
  m.jitter_phases = 16;
  for (int f = 0; f < m.frames; ++f) {
    const Vec2 o = jitter_offset(halton_jitter(16), f);
    m.jitter_offsets.push_back({o.x, o.y});
  }
  write_manifest(dir, m);
  const DatasetManifest r = read_manifest(dir);
  EXPECT_EQ(r.jitter_sequence, "halton");
  EXPECT_EQ(r.jitter_phases, 16);
  EXPECT_EQ(r.jitter_offsets, m.jitter_offsets);
  // Without jitter there is no key: manifests are written as before it.
  m.jitter_sequence.clear();
  m.jitter_offsets.clear();
  write_manifest(dir, m);
  std::ifstream in(dir / "manifest.yaml");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text.find("jitter"), std::string::npos) << text;
  EXPECT_TRUE(read_manifest(dir).jitter_offsets.empty());
}

TEST(Jitter, MalformedOffsetsNameTheManifestAndKey) {
  const fs::path dir = test::scratch_dir("jitter_bad");
  test::expect_manifest_errors(dir, {
      {"jitter: {resolution: 32x24, sequence: halton, phases: 8, offsets: [[0, 0.1]]}", "has 1 offsets for 2 frames"},
      {"jitter: {resolution: 32x24, sequence: halton, phases: 8, offsets: [[0, 0.1], [0.5, 0]]}",
       "outside [-0.5, 0.5) pixels"},
      {"jitter: {resolution: 64x48, sequence: halton, phases: 8, offsets: [[0, 0], [0, 0]]}",
       "only the smallest resolution"},
      {"jitter: {resolution: 32x24, sequence: sobol, phases: 8, offsets: [[0, 0], [0, 0]]}", "unknown jitter sequence"},
      {"jitter: {resolution: 32x24, phases: 8, offsets: [[0, 0], [0, 0]]}", "missing required key 'sequence'"},
  }, "manifest.yaml:11", "jitter");
}

// A jittered render: the smallest resolution's frames carry their offsets through the data set
// to the loader, the larger ones (the ground truth) none; the fingerprint tells it apart, and a
// render with jitter off has the fingerprint it had before the option.
TEST(Jitter, ARenderedDataSetRecordsTheOffsetsAndTheLoaderReadsThem) {
  const fs::path root = test::scratch_dir("jitter_render");
  const auto doc = config::Document::load_file(std::string(CGSR_SOURCE_DIR) + "/configs/scenes/tiny.yaml");
  RenderJobOptions job;
  job.frames = 3;
  job.resolutions = {"32x24", "64x48"};
  job.shadows = false;
  job.scene = config::Block{doc.root()["scene"], std::make_shared<config::Document>(doc), "scene"};
  const std::string plain_fingerprint = render_fingerprint(job, 1);
  JitterSettings off;
  off.phases = 16;  // ignored while the sequence is none
  job.jitter = off;
  EXPECT_EQ(render_fingerprint(job, 1), plain_fingerprint);
  job.jitter = halton_jitter(8);
  EXPECT_NE(render_fingerprint(job, 1), plain_fingerprint);
  const RenderJobResult result = run_render_job(job, 1, root / "set");
  finish_render(root / "set", result.manifest);

  const Dataset data = Dataset::open(root / "set");
  for (int f = 0; f < 3; ++f) {
    const Vec2 o = jitter_offset(job.jitter, f);
    const Frame lr = data.load(f, 0), hr = data.load(f, 1);
    EXPECT_FLOAT_EQ(static_cast<float>(lr.jitter[0]), o.x) << "frame " << f;
    EXPECT_FLOAT_EQ(static_cast<float>(lr.jitter[1]), o.y) << "frame " << f;
    EXPECT_EQ(hr.jitter[0], 0.0);
    EXPECT_EQ(hr.jitter[1], 0.0);
    EXPECT_EQ(crop(lr, 3, 2, 8, 8).jitter, lr.jitter);
  }
  // The LR frame is the jittered view: it differs from an unjittered render of the same pose.
  const SceneBundle b = make_scene(job.scene, 1);
  const SceneRenderer renderer(b.scene, test::unshadowed());
  const GBuffer unjittered = renderer.render(b.camera.at_frame(1, 3), b.camera.at_frame(0, 3), 32, 24,
                                             b.camera.near_plane, b.camera.far_plane);
  const GBuffer jittered = renderer.render(b.camera.at_frame(1, 3), b.camera.at_frame(0, 3), 32, 24,
                                           b.camera.near_plane, b.camera.far_plane, jitter_offset(job.jitter, 1));
  const Frame stored = data.load(1, 0);
  const auto as_u8 = [](const torch::Tensor& c) { return (c.clamp(0, 1) * 255.0f).round().to(torch::kUInt8); };
  EXPECT_TRUE(torch::equal(stored.color, as_u8(jittered.color)));
  EXPECT_FALSE(torch::equal(stored.color, as_u8(unjittered.color)));
}

}  // namespace
}  // namespace cgsr
