// The renderer's G-buffer at known poses: depth, normals, normal angle, LR/HR alignment,
// motion vectors, extreme depth ranges and the sky.
#include <gtest/gtest.h>

#include <torch/torch.h>

#include <cmath>
#include <memory>
#include <string>
#include <tuple>

#include "render_data/camera.h"
#include "render_data/render_channels.h"
#include "render_data/renderer.h"
#include "render_data/scene_source.h"
#include "test_scenes.h"

namespace cgsr {
namespace {

CameraPose looking_down_minus_z(float vfov = 60) {
  CameraPose p;
  p.vfov = vfov;
  return p;
}

TEST(Renderer, FacingPlaneHasConstantDepthAndNormal) {
  Scene s = test::empty_scene();
  // Plane z = -5, facing +z (the camera), much larger than the view.
  test::add_quad(s, {0, 0, -5}, {50, 0, 0}, {0, 50, 0}, 3);
  SceneRenderer r(s, test::unshadowed());
  const int W = 40, H = 30;
  const auto pose = looking_down_minus_z(70);
  const GBuffer g = r.render(pose, pose, W, H, 0.1f, 100.0f);
  const FrameCamera cam = make_frame_camera(pose, W, H, 0.1f, 100.0f);
  auto depth = g.depth.accessor<float, 3>();
  auto normal = g.normal.accessor<float, 3>();
  auto angle = g.normal_angle.accessor<float, 3>();
  auto id = g.object_id.accessor<int32_t, 3>();
  for (int i = 0; i < H; ++i)
    for (int j = 0; j < W; ++j) {
      ASSERT_NEAR(depth[0][i][j], 5.0f, 1e-4f);  // view depth, not distance
      EXPECT_NEAR(normal[0][i][j], 0.0f, 1e-5f);
      EXPECT_NEAR(normal[1][i][j], 0.0f, 1e-5f);
      EXPECT_NEAR(normal[2][i][j], 1.0f, 1e-5f);
      EXPECT_EQ(id[0][i][j], 3);
      // Angle between the normal (0,0,1) and the direction to the camera through this pixel.
      const double u = (j + 0.5 - W / 2.0) / cam.focal_px, v = (H / 2.0 - (i + 0.5)) / cam.focal_px;
      const double expected = std::acos(1.0 / std::sqrt(1 + u * u + v * v)) / (kPiF / 2);
      EXPECT_NEAR(angle[0][i][j], expected, 1e-4);
    }
  EXPECT_LT(g.motion.abs().max().item<float>(), 1e-3f);  // same camera: no motion
}

TEST(Renderer, FloorSeenFromAKnownPoseMatchesRayIntersection) {
  Scene s = test::empty_scene();
  test::add_quad(s, {0, 0, 0}, {0, 0, 3000}, {3000, 0, 0}, 1);  // floor y = 0 facing up
  SceneRenderer r(s, test::unshadowed());
  CameraPose pose;
  pose.position = {1, 2, 3};
  pose.yaw = 30;
  pose.pitch = -25;
  pose.vfov = 60;
  const int W = 32, H = 24;
  const GBuffer g = r.render(pose, pose, W, H, 0.05f, 5000.0f);
  const FrameCamera cam = make_frame_camera(pose, W, H, 0.05f, 5000.0f);
  auto depth = g.depth.accessor<float, 3>();
  auto normal = g.normal.accessor<float, 3>();
  // The floor normal (0,1,0) in view space, from the camera axes (rows of the view matrix).
  const Vec3 n_view{cam.right.y, cam.up.y, -cam.forward.y};
  int floor_pixels = 0;
  for (int i = 0; i < H; ++i)
    for (int j = 0; j < W; ++j) {
      const Vec3 ray = pixel_ray(cam, j + 0.5f, i + 0.5f);  // forward component 1
      if (ray.y >= -1e-3f) {
        EXPECT_TRUE(std::isinf(depth[0][i][j])) << i << "," << j;
        continue;
      }
      const float t = -pose.position.y / ray.y;  // ray parameter = view depth
      ++floor_pixels;
      EXPECT_NEAR(depth[0][i][j], t, 1e-4f * t) << i << "," << j;
      EXPECT_NEAR(normal[0][i][j], n_view.x, 1e-4f);
      EXPECT_NEAR(normal[1][i][j], n_view.y, 1e-4f);
      EXPECT_NEAR(normal[2][i][j], n_view.z, 1e-4f);
    }
  EXPECT_GT(floor_pixels, W * H / 2);
  EXPECT_NEAR(std::sqrt(n_view.x * n_view.x + n_view.y * n_view.y + n_view.z * n_view.z), 1.0f, 1e-5f);
}

TEST(Renderer, LowAndHighResolutionAreAlignedByPixelCentres) {
  Scene s = test::empty_scene();
  test::add_quad(s, {0, 0, -20}, {100, 0, 0}, {0, 100, 0}, 1);        // background wall
  test::add_quad(s, {0.7f, 0.4f, -6}, {0.8f, 0, 0}, {0, 0.6f, 0}, 2);  // small off-centre card
  SceneRenderer r(s, test::unshadowed());
  CameraPose pose;
  pose.position = {0.2f, 0.1f, 0};
  pose.yaw = 4;
  pose.pitch = 3;
  pose.roll = 7;
  const int W = 48, H = 36;
  const GBuffer lr = r.render(pose, pose, W, H, 0.1f, 100.0f);
  const GBuffer hr = r.render(pose, pose, 2 * W, 2 * H, 0.1f, 100.0f);

  // A 3D point projects to matching continuous coordinates: hr = 2 x lr.
  const FrameCamera cl = make_frame_camera(pose, W, H, 0.1f, 100.0f), ch = make_frame_camera(pose, 2 * W, 2 * H, 0.1f, 100.0f);
  for (const Vec3 p : {Vec3{0.7f, 0.4f, -6}, Vec3{-3, 2, -20}, Vec3{1.1f, -0.2f, -6}}) {
    Vec2 a, b;
    float da, db;
    ASSERT_TRUE(project_to_pixel(cl, p, a, da));
    ASSERT_TRUE(project_to_pixel(ch, p, b, db));
    EXPECT_NEAR(b.x, 2 * a.x, 1e-3f);
    EXPECT_NEAR(b.y, 2 * a.y, 1e-3f);
    EXPECT_FLOAT_EQ(da, db);
  }

  // The rendered card's centroid agrees: HR index centroid = 2 x LR index centroid + 0.5.
  auto centroid = [](const GBuffer& g, double& cx, double& cy) {
    auto id = g.object_id.accessor<int32_t, 3>();
    double sx = 0, sy = 0, n = 0;
    for (int i = 0; i < g.height; ++i)
      for (int j = 0; j < g.width; ++j)
        if (id[0][i][j] == 2) sx += j, sy += i, n += 1;
    cx = sx / n;
    cy = sy / n;
    return n;
  };
  double lx, ly, hx, hy;
  const double nl = centroid(lr, lx, ly), nh = centroid(hr, hx, hy);
  ASSERT_GT(nl, 20);
  EXPECT_NEAR(nh / nl, 4.0, 0.6);
  EXPECT_NEAR(hx, 2 * lx + 0.5, 0.25);
  EXPECT_NEAR(hy, 2 * ly + 0.5, 0.25);

  // Every HR pixel centre whose LR source pixel (by (j + 0.5)/2 - 0.5 rounding) is deep inside
  // the wall or the card sees the same depth at both resolutions (planes: depth is smooth).
  auto dl = lr.depth.accessor<float, 3>();
  auto dh = hr.depth.accessor<float, 3>();
  auto il = lr.object_id.accessor<int32_t, 3>();
  auto ih = hr.object_id.accessor<int32_t, 3>();
  int agree = 0, total = 0;
  for (int i = 0; i < 2 * H; ++i)
    for (int j = 0; j < 2 * W; ++j) {
      const int li = std::min(H - 1, (i / 2)), lj = std::min(W - 1, (j / 2));
      if (il[0][li][lj] != ih[0][i][j]) continue;  // near the card border
      ++total;
      agree += std::abs(dl[0][li][lj] - dh[0][i][j]) < 0.05f * dl[0][li][lj];
    }
  EXPECT_GT(total, 4 * W * H * 9 / 10);
  EXPECT_EQ(agree, total);
}

TEST(Renderer, MotionVectorsOfACameraTranslation) {
  Scene s = test::empty_scene();
  test::add_quad(s, {0, 0, -4}, {50, 0, 0}, {0, 50, 0}, 1);
  SceneRenderer r(s, test::unshadowed());
  CameraPose now = looking_down_minus_z(60), before = now;
  now.position = {0.3f, -0.1f, 0};  // the camera moved right and down since the previous frame
  const int W = 32, H = 24;
  const GBuffer g = r.render(now, before, W, H, 0.1f, 100.0f);
  const FrameCamera cam = make_frame_camera(now, W, H, 0.1f, 100.0f);
  // A point seen at p now was at p + f * (camera displacement) / depth before: the camera was to
  // the left and higher, so the point appeared further right and lower (x right, y down).
  const float mx = cam.focal_px * 0.3f / 4.0f, my = cam.focal_px * 0.1f / 4.0f;
  auto m = g.motion.accessor<float, 3>();
  for (int i = 0; i < H; ++i)
    for (int j = 0; j < W; ++j) {
      EXPECT_NEAR(m[0][i][j], mx, 1e-3f);
      EXPECT_NEAR(m[1][i][j], my, 1e-3f);
    }
}

// The camera moved back since the previous frame: the floor just in front of it now was behind
// (or within the near plane of) the previous camera. Those pixels have no previous pixel: motion
// 0 and counted; before the near-plane test, points just in front of the previous camera's plane
// got motions of millions of pixels.
TEST(Renderer, PointsBehindThePreviousCamerasNearPlaneHaveZeroMotionAndAreCounted) {
  Scene s = test::empty_scene();
  test::add_quad(s, {0, -1, -50}, {50, 0, 0}, {0, 0, -50}, 1);  // floor y = -1, z in [-100, 0]
  SceneRenderer r(s, test::unshadowed());
  CameraPose now = looking_down_minus_z(60);
  now.pitch = -30;
  CameraPose before = now;
  before.position = {0, 0, -3};
  const float near_plane = 0.1f, far_plane = 200.0f;
  const int W = 64, H = 48;
  const GBuffer g = r.render(now, before, W, H, near_plane, far_plane);
  const FrameCamera cam = make_frame_camera(now, W, H, near_plane, far_plane);
  const FrameCamera prev = make_frame_camera(before, W, H, near_plane, far_plane);
  auto d = g.depth.accessor<float, 3>();
  auto m = g.motion.accessor<float, 3>();
  int behind = 0, unsure = 0, in_front = 0;
  for (int i = 0; i < H; ++i)
    for (int j = 0; j < W; ++j) {
      if (!std::isfinite(d[0][i][j])) continue;
      const Vec3 world = cam.pose.position + pixel_ray(cam, j + 0.5f, i + 0.5f) * d[0][i][j];
      const float w = dot(world - prev.pose.position, prev.forward);  // view depth in the previous camera
      ASSERT_TRUE(std::isfinite(m[0][i][j]) && std::isfinite(m[1][i][j])) << i << "," << j;
      if (w < near_plane - 1e-3f) {
        ++behind;
        EXPECT_EQ(m[0][i][j], 0.0f) << i << "," << j << " w " << w;
        EXPECT_EQ(m[1][i][j], 0.0f) << i << "," << j << " w " << w;
      } else if (w > near_plane + 1e-3f) {
        ++in_front;
        Vec2 p;
        float depth;
        ASSERT_TRUE(project_to_pixel(prev, world, p, depth));
        // Beyond the guard band the motion is cut (MotionFromFarOutside... covers it).
        if (p.x < -W + 0.01f || p.x > 2 * W - 0.01f || p.y < -H + 0.01f || p.y > 2 * H - 0.01f) continue;
        const float tol = 1e-3f * std::max(1.0f, std::abs(p.x - j - 0.5f) + std::abs(p.y - i - 0.5f));
        EXPECT_NEAR(m[0][i][j], p.x - (j + 0.5f), tol) << i << "," << j;
        EXPECT_NEAR(m[1][i][j], p.y - (i + 0.5f), tol) << i << "," << j;
      } else {
        ++unsure;
      }
    }
  ASSERT_GT(behind, W);  // the scene does put points behind the previous camera
  ASSERT_GT(in_front, W);
  EXPECT_GE(g.motion_rejected, behind);
  EXPECT_LE(g.motion_rejected, behind + unsure);
}

// A still camera rejects nothing; the sky of a turning camera is at the far plane, in front.
TEST(Renderer, NoPixelIsRejectedWhenEveryPointWasInFrontOfThePreviousCamera) {
  Scene s = test::empty_scene();
  test::add_quad(s, {0, 0, -4}, {2, 0, 0}, {0, 2, 0}, 1);
  SceneRenderer r(s, test::unshadowed());
  CameraPose now = looking_down_minus_z(60), before = now;
  EXPECT_EQ(r.render(now, before, 32, 24, 0.1f, 100.0f).motion_rejected, 0);
  now.yaw = 3;
  now.position = {0.1f, 0, 0};
  EXPECT_EQ(r.render(now, before, 32, 24, 0.1f, 100.0f).motion_rejected, 0);
}

// After a fast turn a wall's points were far beside the previous view: each motion keeps its
// direction but ends on the guard band one image size around the previous frame (still outside).
TEST(Renderer, MotionFromFarOutsideThePreviousViewIsCutAtTheGuardBand) {
  Scene s = test::empty_scene();
  test::add_quad(s, {0, 0, -4}, {50, 0, 0}, {0, 50, 0}, 1);
  SceneRenderer r(s, test::unshadowed());
  CameraPose now = looking_down_minus_z(40), before = now;
  before.yaw = 65;
  const float near_plane = 0.1f, far_plane = 100.0f;
  const int W = 32, H = 24;
  const GBuffer g = r.render(now, before, W, H, near_plane, far_plane);
  const FrameCamera cam = make_frame_camera(now, W, H, near_plane, far_plane);
  const FrameCamera prev = make_frame_camera(before, W, H, near_plane, far_plane);
  auto d = g.depth.accessor<float, 3>();
  auto m = g.motion.accessor<float, 3>();
  int cut = 0, kept = 0, behind = 0;
  for (int i = 0; i < H; ++i)
    for (int j = 0; j < W; ++j) {
      const float cx = j + 0.5f, cy = i + 0.5f;
      const Vec3 world = cam.pose.position + pixel_ray(cam, cx, cy) * d[0][i][j];
      Vec2 p;
      float depth;
      if (!project_to_pixel(prev, world, p, depth) || depth < near_plane + 1e-3f) {
        ++behind;  // rejected (motion 0; the other test covers it)
        continue;
      }
      const Vec2 exact{p.x - cx, p.y - cy};
      const Vec2 got{m[0][i][j], m[1][i][j]};
      if (cx + exact.x > 2 * W + 1e-2f) {
        ++cut;
        EXPECT_NEAR(cx + got.x, 2.0f * W, 1e-3f) << i << "," << j;  // on the band's right side
        EXPECT_NEAR(got.y / got.x, exact.y / exact.x, 1e-4f) << i << "," << j;  // same direction
      } else if (cx + exact.x < 2 * W - 1e-2f) {
        ++kept;
        EXPECT_NEAR(got.x, exact.x, 1e-3f * std::max(1.0f, std::abs(exact.x))) << i << "," << j;
        EXPECT_NEAR(got.y, exact.y, 1e-3f * std::max(1.0f, std::abs(exact.y))) << i << "," << j;
      }
    }
  ASSERT_GT(cut, W);  // the turn does put points beyond the band
  ASSERT_GT(kept, 0);
  EXPECT_LE(g.motion_rejected, behind);
  EXPECT_GE(g.motion_clamped, cut);
  EXPECT_LE(g.motion_clamped, W * H - kept);
}

// Along whole camera paths (walls and props pass close to the camera), every motion vector is
// finite and within two image sizes. The held-out hall's path (16 frames, fast turns) has frames
// where the camera passes points that were behind it and points far beside it a frame before:
// rejection and the guard band are exercised, not just absent.
TEST(Renderer, MotionAlongACameraPathStaysWithinAFewImageWidths) {
  for (const auto& [config, seed, step] : {std::tuple{"default", 1, 3}, std::tuple{"heldout_hall", 0, 1}}) {
    SCOPED_TRACE(config);
    const auto doc = config::Document::load_file(std::string(CGSR_SOURCE_DIR) + "/configs/scenes/" + config + ".yaml");
    const config::Block block{doc.root()["scene"], std::make_shared<config::Document>(doc), "scene"};
    const SceneBundle b = make_scene(block, static_cast<uint64_t>(seed));
    const int frames = doc.root()["frames"].as<int>();
    const SceneRenderer r(b.scene, test::unshadowed());
    const int W = 64, H = 48;
    int64_t rejected = 0, clamped = 0;
    for (int f = 0; f < frames; f += step) {
      const GBuffer g = r.render(b.camera.at_frame(f, frames), b.camera.at_frame(f - 1, frames), W, H,
                                 b.camera.near_plane, b.camera.far_plane);
      ASSERT_TRUE(torch::isfinite(g.motion).all().item<bool>()) << "frame " << f;
      EXPECT_LE(g.motion[0].abs().max().item<float>(), 2.0f * W + 1e-3f) << "frame " << f;
      EXPECT_LE(g.motion[1].abs().max().item<float>(), 2.0f * H + 1e-3f) << "frame " << f;
      rejected += g.motion_rejected;
      clamped += g.motion_clamped;
    }
    if (std::string(config) == "heldout_hall") {
      EXPECT_GT(rejected, 0);
      EXPECT_GT(clamped, 0);
    }
  }
}

TEST(Renderer, SkyHasInfiniteDepthAndRotationalMotion) {
  Scene s = test::empty_scene();
  SceneRenderer r(s, test::unshadowed());
  CameraPose now = looking_down_minus_z(60), before = now;
  now.yaw = 2;  // turned left: the world (and the sky) moves right on screen, so it was left before
  const GBuffer g = r.render(now, before, 16, 12, 0.1f, 100.0f);
  EXPECT_TRUE(torch::isinf(g.depth).all().item<bool>());
  EXPECT_EQ(g.normal.abs().max().item<float>(), 0.0f);
  EXPECT_EQ(g.edge.max().item<float>(), 0.0f);
  EXPECT_TRUE((g.object_id == -1).all().item<bool>());
  EXPECT_LT(g.motion[0].max().item<float>(), 0.0f);
  const auto nd = normalize_depth(g.depth, 0.1, 100.0);
  EXPECT_TRUE((nd == 1.0f).all().item<bool>());
}

TEST(Renderer, ExtremeDepthRange) {
  Scene s = test::empty_scene();
  test::add_quad(s, {0, 0, -1e5f}, {1e6f, 0, 0}, {0, 1e6f, 0}, 1);           // very far wall
  test::add_quad(s, {0, 0, -2e-3f}, {1e-4f, 0, 0}, {0, 1e-4f, 0}, 2);        // tiny card at 2 mm
  SceneRenderer r(s, test::unshadowed());
  const auto pose = looking_down_minus_z(60);
  const int W = 32, H = 24;
  const GBuffer g = r.render(pose, pose, W, H, 1e-3f, 1e6f);
  auto d = g.depth.accessor<float, 3>();
  EXPECT_NEAR(d[0][H / 2][W / 2], 2e-3f, 1e-6f);
  EXPECT_NEAR(d[0][0][0], 1e5f, 10.0f);
  EXPECT_TRUE(torch::isfinite(g.depth).all().item<bool>());
  const auto nd = normalize_depth(g.depth, 1e-3, 1e6);
  EXPECT_TRUE(torch::isfinite(nd).all().item<bool>());
  EXPECT_GE(nd.min().item<float>(), 0.0f);
  EXPECT_LE(nd.max().item<float>(), 1.0f);
  EXPECT_LT(nd[0][H / 2][W / 2].item<float>(), nd[0][0][0].item<float>());
  // The near card's silhouette is an edge against the far wall.
  EXPECT_GT(g.edge.sum().item<float>(), 0.0f);
}

TEST(Renderer, TexturedSurfacesUseMipmapsAtADistance) {
  // A fine checkerboard floor receding into the distance: far away the mip chain averages the
  // checker to grey instead of aliasing to black or white.
  Scene s = test::empty_scene();
  Texture t;
  t.width = t.height = 64;
  t.data.resize(64 * 64 * 3);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x)
      for (int c = 0; c < 3; ++c) t.data[(y * 64 + x) * 3 + c] = ((x + y) % 2) ? 255 : 0;
  s.textures.push_back(t);
  s.materials[0].albedo_texture = 0;
  s.materials[0].unlit = true;
  Mesh m;
  m.positions = {{-50, 0, 0}, {50, 0, 0}, {50, 0, -400}, {-50, 0, -400}};
  m.normals = {{0, 1, 0}, {0, 1, 0}, {0, 1, 0}, {0, 1, 0}};
  m.uvs = {{0, 0}, {25, 0}, {25, 100}, {0, 100}};
  m.indices = {0, 1, 2, 0, 2, 3};
  s.meshes.push_back(m);
  SceneRenderer r(s, test::unshadowed());
  CameraPose pose = looking_down_minus_z(60);
  pose.position = {0, 1, 0};
  const GBuffer g = r.render(pose, pose, 64, 48, 0.1f, 1000.0f);
  // Rows just below the horizon are far away: their colour is a mid grey (sRGB of 0.5 linear).
  auto c = g.color.accessor<float, 3>();
  const int row = 48 / 2 + 1;
  for (int j = 8; j < 56; ++j) EXPECT_NEAR(c[0][row][j], 0.735f, 0.06f) << "col " << j;
}

TEST(Renderer, ShadowMapsDarkenOccludedSurfaces) {
  Scene s = test::empty_scene();
  s.lights.clear();
  s.ambient = {0.05f, 0.05f, 0.05f};
  Light sun;
  sun.type = LightType::Directional;
  sun.direction = {0, -1, 0};
  sun.shadows = true;
  s.lights.push_back(sun);
  test::add_quad(s, {0, 0, -10}, {0, 0, 10}, {10, 0, 0}, 1);       // floor
  test::add_quad(s, {0, 2, -10}, {1.5f, 0, 0}, {0, 0, -1.5f}, 2);  // roof above the floor centre
  CameraPose pose;
  pose.position = {0, 6, 0};
  pose.pitch = -45;
  RenderSettings with = test::unshadowed();
  with.shadows = true;
  const GBuffer lit = SceneRenderer(s, test::unshadowed()).render(pose, pose, 64, 48, 0.1f, 100.0f);
  const GBuffer shadowed = SceneRenderer(s, with).render(pose, pose, 64, 48, 0.1f, 100.0f);
  // Floor pixels under the roof: project the floor point below the roof centre.
  const FrameCamera cam = make_frame_camera(pose, 64, 48, 0.1f, 100.0f);
  Vec2 px;
  float d;
  // A floor point beside the roof (visible, not under the roof in view) and one far from it.
  ASSERT_TRUE(project_to_pixel(cam, {3.5f, 0, -10}, px, d));
  const int i = static_cast<int>(px.y), j = static_cast<int>(px.x);
  const float open = lit.color[0][i][j].item<float>();
  EXPECT_NEAR(shadowed.color[0][i][j].item<float>(), open, 1e-5f);  // open floor: unchanged
  // Somewhere the floor is in the roof's shadow: darker with shadows than without.
  const auto floor = shadowed.object_id[0] == 1;
  const auto darker = (lit.color[0] - shadowed.color[0]).gt(0.2f) & floor;
  EXPECT_GT(darker.sum().item<int64_t>(), 10);
}

}  // namespace
}  // namespace cgsr
