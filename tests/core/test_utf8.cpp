// UTF-8 validation: what JSON writers would refuse at the end of a command is found at its start.
#include <gtest/gtest.h>

#include "core/config.h"
#include "core/error.h"
#include "core/utf8.h"

using namespace cgsr;

TEST(Utf8, WellFormedTextPasses) {
  EXPECT_FALSE(first_invalid_utf8(""));
  EXPECT_FALSE(first_invalid_utf8("plain ascii"));
  EXPECT_FALSE(first_invalid_utf8("caf\xC3\xA9 \xE2\x82\xAC \xF0\x9F\x98\x80"));  // é, €, an emoji
  EXPECT_FALSE(first_invalid_utf8("\xF4\x8F\xBF\xBF"));                           // U+10FFFF
}

TEST(Utf8, MalformedBytesAreFoundAtTheirOffset) {
  EXPECT_EQ(first_invalid_utf8("ab\xFF"), 2u);
  EXPECT_EQ(first_invalid_utf8("caf\xE9"), 3u);              // Latin-1
  EXPECT_EQ(first_invalid_utf8("\xC0\x80"), 0u);             // overlong NUL
  EXPECT_EQ(first_invalid_utf8("\xE0\x80\xAF"), 0u);         // overlong
  EXPECT_EQ(first_invalid_utf8("x\xED\xA0\x80"), 1u);        // a surrogate
  EXPECT_EQ(first_invalid_utf8("\xF4\x90\x80\x80"), 0u);     // beyond U+10FFFF
  EXPECT_EQ(first_invalid_utf8("\xE2\x82"), 0u);             // cut short
  EXPECT_EQ(first_invalid_utf8("\xE2\x82" "a"), 0u);         // a continuation byte missing
}

TEST(Utf8, RequireNamesWhatAndTheByte) {
  try {
    require_utf8("runs/caf\xE9", "--out", "the path");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::User);
    EXPECT_NE(std::string(e.what()).find("--out: the path is not valid UTF-8 (byte 0xE9 at offset 8)"), std::string::npos)
        << e.what();
  }
}

// A config value (a name) that is not UTF-8 used to pass every check and fail with exit 1 when
// results.json was written; now the config is refused where the byte is.
TEST(Utf8, ConfigTextThatIsNotUtf8IsRefusedWithItsPosition) {
  try {
    config::Document::parse("seed: 3\nname: caf\xE9\n", "run.yaml");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("run.yaml:2:10: not valid UTF-8 (byte 0xE9)"), std::string::npos) << e.what();
  }
  config::Document doc;
  EXPECT_THROW(doc.apply_override("name=caf\xE9"), Error);
}
