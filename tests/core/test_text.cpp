#include <gtest/gtest.h>

#include "core/error.h"
#include "core/text.h"

using namespace cgsr;

TEST(Text, EditDistance) {
  EXPECT_EQ(edit_distance("kitten", "sitting"), 3u);
  EXPECT_EQ(edit_distance("", "abc"), 3u);
  EXPECT_EQ(edit_distance("same", "same"), 0u);
}

TEST(Text, SuggestsOnlyPlausibleTypos) {
  const std::vector<std::string> keys{"frames", "resolutions", "seed"};
  EXPECT_EQ(closest_match("framse", keys), "frames");
  EXPECT_EQ(closest_match("resolution", keys), "resolutions");
  EXPECT_EQ(closest_match("completely_different", keys), "");
}

TEST(Text, ParseSize) {
  EXPECT_EQ(parse_size("320x240", "--input"), std::make_pair(320, 240));
  EXPECT_THROW(parse_size("320", "--input"), Error);
  EXPECT_THROW(parse_size("0x10", "--input"), Error);
  EXPECT_THROW(parse_size("axb", "--input"), Error);
  EXPECT_THROW(parse_size("-3x4", "--input"), Error);
  try {
    parse_size("320x0", "--input");
    FAIL() << "a zero height accepted";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "--input: size 320x0: height '0' is out of range [1, 999999]");
  }
}
