// Entity strings: key/value blocks, spawn points and items, and errors that name the line.
#include <gtest/gtest.h>

#include "core/error.h"
#include "render_data/q3/entities.h"
#include "tests/render_data/q3_test_map.h"

namespace cgsr::q3 {
namespace {

std::string error_of(const std::string& text) {
  try {
    parse_entities(text, "maps/x.bsp: entities");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(Q3Entities, ParsesBlocksSpawnPointsAndItems) {
  const auto entities = parse_entities(testing::make_test_map().bsp.entities, "tiny");
  ASSERT_EQ(entities.size(), 6u);
  EXPECT_EQ(entities[0].classname(), "worldspawn");
  EXPECT_EQ(entities[0].get("message"), "tiny");
  EXPECT_EQ(entities[0].get("absent", "fallback"), "fallback");
  int spawns = 0, items = 0;
  for (const auto& e : entities) {
    spawns += is_spawn_point(e);
    items += is_item(e);
  }
  EXPECT_EQ(spawns, 2);
  EXPECT_EQ(items, 2);
  const auto origin = entities[1].vector("origin", "tiny");
  ASSERT_TRUE(origin.has_value());
  EXPECT_TRUE(testing::same(*origin, Vec3{-128, -128, 24}));
  EXPECT_FLOAT_EQ(entities[1].yaw_degrees("tiny"), 45);
  EXPECT_FLOAT_EQ(entities[2].yaw_degrees("tiny"), 0);
  EXPECT_FALSE(entities[0].vector("origin", "tiny").has_value());
  EXPECT_EQ(entities[1].line, 5);
}

TEST(Q3Entities, AnglesAndUnquotedTokens) {
  const auto e = parse_entities("{ classname info_player_start \"angles\" \"0 90 0\" origin \"1 2 3\" }", "x");
  ASSERT_EQ(e.size(), 1u);
  EXPECT_TRUE(is_spawn_point(e[0]));
  EXPECT_FLOAT_EQ(e[0].yaw_degrees("x"), 90);
  EXPECT_FALSE(is_item(e[0]));
}

TEST(Q3Entities, MalformedTextIsAnErrorWithTheLine) {
  EXPECT_NE(error_of("{\n\"classname\" \"a\n").find("line 2: unterminated"), std::string::npos);
  EXPECT_NE(error_of("{\n\"classname\"\n}").find("has no value"), std::string::npos);
  EXPECT_NE(error_of("{\n\"classname\" \"light\"\n").find("not closed"), std::string::npos);
  EXPECT_NE(error_of("\"classname\" \"light\"").find("expected '{'"), std::string::npos);
  EXPECT_NE(error_of("{ \"a\" { }").find("line 1"), std::string::npos);
  const auto bad = parse_entities("{ \"classname\" \"item_health\" \"origin\" \"1 2 nope\" }", "x");
  EXPECT_THROW(bad[0].vector("origin", "x"), Error);
}

}  // namespace
}  // namespace cgsr::q3
