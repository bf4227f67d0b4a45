// The camera path through the tiny room: waypoints at eye height, keys that never touch a wall
// or a drawn surface, continuous orientation, counted drops, and seeded reproducibility.
#include <gtest/gtest.h>

#include "core/error.h"
#include "render_data/q3/camera_path.h"
#include "tests/render_data/q3_test_map.h"

namespace cgsr::q3 {
namespace {

// The room's drawn triangles: the pyramid (the room's walls are brushes already).
SurfaceObstacles pyramid(const testing::TestMap& map) {
  const BspFace& f = map.bsp.faces[map.mesh_face];
  std::vector<std::array<Vec3, 3>> triangles;
  for (int k = 0; k < f.mesh_vert_count; k += 3) {
    std::array<Vec3, 3> t;
    for (int i = 0; i < 3; ++i) t[i] = map.bsp.vertices[f.first_vertex + map.bsp.mesh_verts[f.first_mesh_vert + k + i]].position;
    triangles.push_back(t);
  }
  return SurfaceObstacles(triangles);
}

QuakeCameraPath build(const testing::TestMap& map, const std::string& entities, uint64_t seed, float length = 1500) {
  const BspCollision collision(map.bsp);
  const SurfaceObstacles obstacles = pyramid(map);
  CameraPathOptions o;
  o.length = length;
  o.seed = seed;
  return build_camera_path(parse_entities(entities, "tiny"), collision, obstacles, o, "tiny");
}

TEST(Q3CameraPath, KeysStayInsideTheRoomAwayFromSurfacesAtEyeHeight) {
  const auto map = testing::make_test_map();
  const QuakeCameraPath path = build(map, map.bsp.entities, 1);
  const CameraPathReport& r = path.report;
  EXPECT_EQ(r.candidates, 4);
  EXPECT_EQ(r.waypoints, 4);
  EXPECT_EQ(r.dropped(), 0);
  EXPECT_GT(r.navigation_nodes, 0);
  EXPECT_FALSE(r.turntable);
  EXPECT_NEAR(r.length, 1500, 1);
  ASSERT_GT(path.keys.size(), 100u);

  const BspCollision collision(map.bsp);
  const SurfaceObstacles obstacles = pyramid(map);
  const CameraPathOptions o;
  for (size_t k = 0; k < path.keys.size(); ++k) {
    const QuakeCameraKey& key = path.keys[k];
    EXPECT_FALSE(collision.box_in_solid(key.position, o.hull_half)) << "key " << k;
    EXPECT_GE(obstacles.distance(key.position, o.clearance), 0.75f * o.clearance - 0.01f) << "key " << k;
    EXPECT_NEAR(key.position.z, 50.125f, 0.01f);  // floor 0 + player origin 24 (+0.125) + eye 26
    EXPECT_LE(std::abs(key.pitch), o.max_pitch);
    if (k == 0) continue;
    const QuakeCameraKey& prev = path.keys[k - 1];
    EXPECT_GT(key.distance, prev.distance);
    EXPECT_FALSE(collision.trace(prev.position, key.position, o.hull_half).hit()) << "key " << k;
    EXPECT_LT(length(key.position - prev.position), 2 * o.key_spacing);
    // Continuous yaw: the turn rate limit plus the sway's slope bound each step.
    EXPECT_LT(std::abs(key.yaw - prev.yaw), 10.0f) << "key " << k;
  }
}

TEST(Q3CameraPath, TheSameSeedGivesTheSamePath) {
  const auto map = testing::make_test_map();
  const auto a = build(map, map.bsp.entities, 7), b = build(map, map.bsp.entities, 7);
  const auto c = build(map, map.bsp.entities, 8);
  ASSERT_EQ(a.keys.size(), b.keys.size());
  for (size_t k = 0; k < a.keys.size(); ++k) {
    EXPECT_TRUE(testing::same(a.keys[k].position, b.keys[k].position));
    EXPECT_EQ(a.keys[k].yaw, b.keys[k].yaw);
  }
  bool differs = false;
  for (size_t k = 0; k < std::min(a.keys.size(), c.keys.size()); ++k)
    differs |= a.keys[k].yaw != c.keys[k].yaw || !testing::same(a.keys[k].position, c.keys[k].position);
  EXPECT_TRUE(differs);
}

TEST(Q3CameraPath, UnusableWaypointsAreDroppedAndCounted) {
  const auto map = testing::make_test_map();
  const std::string entities =
      "{ \"classname\" \"info_player_deathmatch\" \"origin\" \"-128 -128 24\" }\n"
      "{ \"classname\" \"item_armor_shard\" \"origin\" \"264 0 100\" }\n"     // inside the +x wall
      "{ \"classname\" \"item_health\" \"origin\" \"0 0 -300\" }\n"           // below the world
      "{ \"classname\" \"weapon_railgun\" \"origin\" \"-120 -120 24\" }\n"    // merged with the spawn
      "{ \"classname\" \"ammo_slugs\" \"origin\" \"128 128 80\" }\n"          // on the pyramid's tip
      "{ \"classname\" \"item_quad\" \"origin\" \"100 -100 24\" }\n";
  const QuakeCameraPath path = build(map, entities, 1, 600);
  const CameraPathReport& r = path.report;
  EXPECT_EQ(r.candidates, 6);
  EXPECT_EQ(r.dropped_in_solid, 1);
  EXPECT_EQ(r.dropped_no_floor + r.dropped_outside, 1);
  EXPECT_EQ(r.merged, 1);
  EXPECT_EQ(r.dropped_near_surface, 1);
  EXPECT_EQ(r.waypoints, 2);
  EXPECT_NE(r.summary().find("1 merged"), std::string::npos);
}

TEST(Q3CameraPath, OneWaypointTurnsOnTheSpotAndNoneIsAnError) {
  const auto map = testing::make_test_map();
  const QuakeCameraPath path = build(map, "{ \"classname\" \"info_player_start\" \"origin\" \"0 -128 24\" }", 3);
  EXPECT_TRUE(path.report.turntable);
  ASSERT_GE(path.keys.size(), 2u);
  EXPECT_TRUE(testing::same(path.keys.front().position, path.keys.back().position));
  EXPECT_NEAR(path.keys.back().yaw - path.keys.front().yaw, 360.0f, 1e-3);
  EXPECT_THROW(build(map, "{ \"classname\" \"worldspawn\" }", 3), Error);
}

}  // namespace
}  // namespace cgsr::q3
