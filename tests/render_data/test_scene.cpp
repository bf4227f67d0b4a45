// Scene description helpers: camera path interpolation and scene validation.
#include <gtest/gtest.h>

#include "core/error.h"
#include "render_data/scene.h"
#include "test_scenes.h"

namespace cgsr {
namespace {

CameraPath three_keys() {
  CameraPath p;
  for (int k = 0; k < 3; ++k) {
    CameraKey key;
    key.time = k == 2 ? 4.0 : k;  // a slow last stretch
    key.pose.position = {static_cast<float>(k), 0, static_cast<float>(-k)};
    key.pose.yaw = 30.0f * k;
    key.pose.vfov = 60;
    p.keys.push_back(key);
  }
  return p;
}

TEST(CameraPath, PassesThroughKeysAndClampsOutside) {
  const CameraPath p = three_keys();
  for (const auto& k : p.keys) {
    const CameraPose at = p.at_time(k.time);
    EXPECT_FLOAT_EQ(at.position.x, k.pose.position.x);
    EXPECT_FLOAT_EQ(at.yaw, k.pose.yaw);
  }
  EXPECT_FLOAT_EQ(p.at_time(-3).position.x, 0.0f);
  EXPECT_FLOAT_EQ(p.at_time(10).position.x, 2.0f);
  // Frames span the whole path; frame -1 (the previous of frame 0) clamps to the start.
  EXPECT_FLOAT_EQ(p.at_frame(0, 5).position.x, 0.0f);
  EXPECT_FLOAT_EQ(p.at_frame(4, 5).position.x, 2.0f);
  EXPECT_FLOAT_EQ(p.at_frame(-1, 5).position.x, 0.0f);
}

TEST(CameraPath, IsSmoothAndSlowsDownOnLongSegments) {
  const CameraPath p = three_keys();
  // Speed on the first segment (1 unit per 1 s) vs the last (1 unit per 3 s).
  const float fast = length(p.at_time(0.6).position - p.at_time(0.4).position);
  const float slow = length(p.at_time(3.1).position - p.at_time(2.9).position);
  EXPECT_GT(fast, 1.5f * slow);
  // No jump across a key: velocity just before and after key 1 agree.
  const Vec3 before = (p.at_time(1.0).position - p.at_time(0.99).position) / 0.01f;
  const Vec3 after = (p.at_time(1.01).position - p.at_time(1.0).position) / 0.01f;
  EXPECT_LT(length(before - after), 0.1f * length(before));
}

TEST(CameraPath, ValidationNamesTheKey) {
  CameraPath p = three_keys();
  p.keys[2].time = 0.5;
  try {
    validate_camera_path(p, "scene 'x'");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("camera key 2"), std::string::npos) << e.what();
  }
  p = three_keys();
  p.far_plane = p.near_plane;
  EXPECT_THROW(validate_camera_path(p, "scene"), Error);
}

TEST(Scene, ValidationNamesTheMesh) {
  Scene s = test::empty_scene("broken");
  test::add_triangle(s, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 1);
  validate_scene(s);
  s.meshes[0].indices[2] = 7;
  try {
    validate_scene(s);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("mesh 0"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("index 7 out of range"), std::string::npos) << e.what();
  }
  s.meshes[0].indices[2] = 2;
  s.meshes[0].positions[1].x = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(validate_scene(s), Error);
}

}  // namespace
}  // namespace cgsr
