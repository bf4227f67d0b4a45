// Box traces against the brushes of the tiny room.
#include <gtest/gtest.h>

#include "render_data/q3/bsp_trace.h"
#include "tests/render_data/q3_test_map.h"

namespace cgsr::q3 {
namespace {

TEST(Q3BspTrace, BoxStopsAtTheWallItWouldCross) {
  const auto map = testing::make_test_map();
  const BspCollision collision(map.bsp);
  const Vec3 half{16, 16, 8};
  // From the centre towards the +x wall (its inner face is x = 256): the box stops when its
  // side touches the wall, 16 units before it (less the game's 0.125 safety gap).
  const TraceResult r = collision.trace({0, 0, 100}, {400, 0, 100}, half);
  EXPECT_FALSE(r.start_solid);
  ASSERT_LT(r.fraction, 1.0f);
  EXPECT_NEAR(r.end.x, 240.0f - 0.125f, 0.01f);
  EXPECT_TRUE(testing::same(r.normal, Vec3{-1, 0, 0}));

  const TraceResult free = collision.trace({-100, -100, 100}, {100, 120, 150}, half);
  EXPECT_FALSE(free.hit());
  EXPECT_TRUE(testing::same(free.end, Vec3{100, 120, 150}));

  // Falling onto the floor (z = 0) with a player box (24 below its origin).
  const TraceResult fall = collision.trace({0, 0, 100}, {0, 0, -500}, {15, 15, 24});
  EXPECT_NEAR(fall.end.z, 24.125f, 0.01f);
  EXPECT_TRUE(testing::same(fall.normal, Vec3{0, 0, 1}));
}

TEST(Q3BspTrace, SolidPointsLeavesAndClusters) {
  const auto map = testing::make_test_map();
  const BspCollision collision(map.bsp);
  EXPECT_TRUE(collision.box_in_solid({260, 0, 100}, {0, 0, 0}));     // inside the +x wall
  EXPECT_TRUE(collision.box_in_solid({250, 0, 100}, {16, 16, 16}));  // overlapping it
  EXPECT_FALSE(collision.box_in_solid({0, 0, 100}, {16, 16, 16}));
  EXPECT_EQ(collision.leaf_at({0, 0, 100}), 0);
  EXPECT_EQ(collision.cluster_at({0, 0, 100}), 0);
  EXPECT_EQ(collision.leaf_at({0, 0, -600}), 1);
  EXPECT_EQ(collision.cluster_at({0, 0, -600}), -1);
  // Brushes whose contents are outside the mask do not block.
  const BspCollision water_only(map.bsp, contents::kWater);
  EXPECT_FALSE(water_only.box_in_solid({260, 0, 100}, {0, 0, 0}));
  EXPECT_FALSE(water_only.trace({0, 0, 100}, {400, 0, 100}, {16, 16, 8}).hit());
}

}  // namespace
}  // namespace cgsr::q3
