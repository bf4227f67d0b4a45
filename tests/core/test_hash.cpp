#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/hash.h"

using namespace cgsr;

TEST(Hash, Fnv1a64PublishedTestVectors) {
  EXPECT_EQ(fnv1a64(""), 0xcbf29ce484222325ull);  // the empty string hashes to the basis
  EXPECT_EQ(fnv1a64("a"), 0xaf63dc4c8601ec8cull);
  EXPECT_EQ(fnv1a64("foobar"), 0x85944171f73967e8ull);
}

TEST(Hash, HighBytesAreHashedAsUnsigned) {
  // A signed char would sign-extend 0xff into the xor and change the result.
  EXPECT_EQ(fnv1a64(std::string(1, '\xff')), (kFnv1a64OffsetBasis ^ 0xffull) * kFnv1a64Prime);
}

TEST(Hash, LegacyBasisReproducesTheOldCopies) {
  // The loop the seed, fingerprint and cache-key code carried before it called fnv1a64.
  const auto old_loop = [](const std::string& text) {
    uint64_t h = 1469598103934665603ULL;
    for (unsigned char c : text) h = (h ^ c) * 1099511628211ULL;
    return h;
  };
  const std::vector<std::string> texts{"", "patch_sampler", "backbone: pan\nscale: 2\n", std::string("\x00\xff\x80", 3)};
  for (const auto& text : texts)
    EXPECT_EQ(fnv1a64(text, kLegacyFnv1a64Basis), old_loop(text)) << text;
  // Pinned values: a change here changes every reproduced seed and cache key.
  EXPECT_EQ(fnv1a64("", kLegacyFnv1a64Basis), 1469598103934665603ull);
  EXPECT_EQ(fnv1a64("a", kLegacyFnv1a64Basis), (1469598103934665603ull ^ 'a') * 1099511628211ull);
}
