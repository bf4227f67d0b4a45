// The BSP parser and everything that walks a parsed map (geometry, traces) on thousands of
// seeded mutations and truncations of the tiny map: each input either loads or is a cgsr::Error,
// never a crash (run under -DCGSR_SANITIZE=ON for the sanitizer's view; fuzz/fuzz_bsp.cpp is the
// coverage-guided version).
#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "core/error.h"
#include "render_data/q3/bezier_patch.h"
#include "render_data/q3/bsp_trace.h"
#include "render_data/q3/entities.h"
#include "tests/render_data/q3_test_map.h"

namespace cgsr::q3 {
namespace {

// Uses a parsed map the way the loader does: tessellate patches, walk faces, trace the tree.
size_t exercise(const BspFile& bsp) {
  size_t work = 0;
  for (const BspFace& f : bsp.faces) {
    if (f.type == FaceType::Patch) {
      const std::vector<BspVertex> control(bsp.vertices.begin() + f.first_vertex,
                                           bsp.vertices.begin() + f.first_vertex + f.vertex_count);
      work += tessellate_patch(control, f.patch_size[0], f.patch_size[1], 2).indices.size();
    } else if (f.type != FaceType::Billboard) {
      for (int k = 0; k < f.mesh_vert_count; ++k)
        work += bsp.vertices[f.first_vertex + bsp.mesh_verts[f.first_mesh_vert + k]].color[0];
    }
  }
  const BspCollision collision(bsp);
  work += collision.trace({-300, -300, 50}, {300, 300, 100}, {16, 16, 8}).hit();
  work += collision.leaf_at({0, 0, 0});
  try {
    work += parse_entities(bsp.entities, bsp.name).size();
  } catch (const Error&) {
  }
  return work;
}

TEST(Q3BspFuzz, MutatedAndTruncatedMapsLoadOrFailCleanly) {
  const std::vector<uint8_t> original = testing::write_bsp(testing::make_test_map().bsp);
  std::mt19937_64 rng(20240611);
  int loaded = 0, rejected = 0;
  const int rounds = 3000;
  for (int round = 0; round < rounds; ++round) {
    std::vector<uint8_t> bytes = original;
    switch (round % 4) {
      case 0: {  // flip a few random bytes
        const int flips = 1 + static_cast<int>(rng() % 8);
        for (int i = 0; i < flips; ++i) bytes[rng() % bytes.size()] ^= static_cast<uint8_t>(1 + rng() % 255);
        break;
      }
      case 1: {  // overwrite an aligned 32-bit field with a nasty value
        const int32_t nasty[] = {-1, 0, 1, 2, 3, 64, 65, 1 << 20, INT32_MAX, INT32_MIN, 0x7fc00000 /* NaN */};
        const size_t at = (rng() % (bytes.size() / 4)) * 4;
        std::memcpy(&bytes[at], &nasty[rng() % (sizeof nasty / sizeof nasty[0])], 4);
        break;
      }
      case 2:  // truncate
        bytes.resize(rng() % bytes.size());
        break;
      case 3: {  // corrupt the lump directory
        const size_t entry = 8 + (rng() % (kLumpCount * 2)) * 4;
        const int32_t value = static_cast<int32_t>(rng() % (bytes.size() + 64)) - 32;
        std::memcpy(&bytes[entry], &value, 4);
        break;
      }
    }
    try {
      const BspFile bsp = parse_bsp(bytes, "maps/fuzz.bsp");
      exercise(bsp);
      ++loaded;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("maps/fuzz.bsp"), std::string::npos) << e.what();
      ++rejected;
    }
  }
  EXPECT_EQ(loaded + rejected, rounds);
  EXPECT_GT(rejected, rounds / 10);  // the mutations do reach the validation
  EXPECT_GT(loaded, 0);              // and some survive it (e.g. flipped texture names or colours)
}

}  // namespace
}  // namespace cgsr::q3
