// parse_bsp: every lump of the tiny test map round-trips, and corrupt files (wrong magic or
// version, truncated lumps, out-of-range indices, non-finite numbers) are errors naming the file
// and the lump.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "core/error.h"
#include "render_data/q3/bsp_file.h"
#include "tests/render_data/q3_test_map.h"

namespace cgsr::q3 {
namespace {

using testing::make_test_map;
using testing::write_bsp;

// The error message of parsing `bytes`, or "" when it parses.
std::string parse_error(const std::vector<uint8_t>& bytes) {
  try {
    parse_bsp(bytes, "maps/tiny.bsp");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}
std::string parse_error(const BspFile& bsp) { return parse_error(write_bsp(bsp)); }

void expect_mentions(const std::string& message, std::initializer_list<const char*> parts) {
  ASSERT_FALSE(message.empty()) << "expected an error";
  for (const char* part : parts) EXPECT_NE(message.find(part), std::string::npos) << message << " lacks " << part;
}

int32_t read_i32(const std::vector<uint8_t>& b, size_t at) {
  int32_t v;
  std::memcpy(&v, &b[at], 4);
  return v;
}

TEST(Q3BspFile, EveryLumpRoundTrips) {
  const auto map = make_test_map();
  const BspFile b = parse_bsp(write_bsp(map.bsp), "maps/tiny.bsp");
  EXPECT_EQ(b.entities, map.bsp.entities);
  ASSERT_EQ(b.textures.size(), map.bsp.textures.size());
  EXPECT_EQ(b.textures[2].name, "textures/test/sky");
  EXPECT_EQ(b.textures[2].surface_flags & surface_flags::kSky, surface_flags::kSky);
  EXPECT_EQ(b.planes.size(), map.bsp.planes.size());
  EXPECT_EQ(b.nodes[0].children, (std::array<int, 2>{-1, -2}));
  EXPECT_EQ(b.leafs.size(), 2u);
  EXPECT_EQ(b.leafs[0].leaf_brush_count, 6);
  EXPECT_EQ(b.leaf_faces.size(), map.bsp.faces.size());
  EXPECT_EQ(b.brushes.size(), 6u);
  EXPECT_EQ(b.brush_sides.size(), 36u);
  ASSERT_EQ(b.vertices.size(), map.bsp.vertices.size());
  for (size_t i = 0; i < b.vertices.size(); ++i) {
    EXPECT_EQ(b.vertices[i].position.x, map.bsp.vertices[i].position.x);
    EXPECT_EQ(b.vertices[i].lightmap_uv.y, map.bsp.vertices[i].lightmap_uv.y);
    EXPECT_EQ(b.vertices[i].color, map.bsp.vertices[i].color);
  }
  EXPECT_EQ(b.mesh_verts, map.bsp.mesh_verts);
  ASSERT_EQ(b.faces.size(), map.bsp.faces.size());
  EXPECT_EQ(b.faces[map.patch_face].type, FaceType::Patch);
  EXPECT_EQ(b.faces[map.patch_face].patch_size, (std::array<int, 2>{3, 3}));
  EXPECT_EQ(b.faces[map.mesh_face].lightmap, -3);
  EXPECT_EQ(b.faces[map.billboard_face].type, FaceType::Billboard);
  ASSERT_EQ(b.lightmaps.size(), 1u);
  EXPECT_EQ(b.lightmaps[0].rgb.size(), 128u * 128 * 3);
  EXPECT_EQ(b.lightmaps[0].rgb[3 * 500 + 1], map.lightmap_texel[1]);
  ASSERT_EQ(b.light_volumes.size(), 1u);
  EXPECT_EQ(b.light_volumes[0].direction, (std::array<uint8_t, 2>{7, 8}));
  EXPECT_EQ(b.effects[0].name, "textures/test/fog");
  EXPECT_EQ(b.vis.cluster_count, 1);
  EXPECT_TRUE(b.vis.visible(0, 0));
  EXPECT_EQ(b.models[0].face_count, static_cast<int>(b.faces.size()));
  EXPECT_EQ(b.non_finite_coordinates, 0);
  EXPECT_EQ(b.tree_depth, 1);
}

TEST(Q3BspFile, WrongMagicVersionOrSizeIsAHeaderError) {
  auto bytes = write_bsp(make_test_map().bsp);
  auto bad_magic = bytes;
  bad_magic[0] = 'X';
  expect_mentions(parse_error(bad_magic), {"maps/tiny.bsp", "header", "magic"});
  auto bad_version = bytes;
  bad_version[4] = 47;
  expect_mentions(parse_error(bad_version), {"maps/tiny.bsp", "header", "47"});
  expect_mentions(parse_error(std::vector<uint8_t>(bytes.begin(), bytes.begin() + 100)), {"header", "shorter"});
  expect_mentions(parse_error(std::vector<uint8_t>{}), {"header"});
}

TEST(Q3BspFile, TruncatedLumpsNameTheLump) {
  const auto bytes = write_bsp(make_test_map().bsp);
  // Cut the file inside the faces lump (13) and inside the lightmaps lump (14).
  for (const auto& [lump, name] : {std::pair{13, "faces"}, std::pair{14, "lightmaps"}}) {
    const size_t offset = read_i32(bytes, 8 + lump * 8), length = read_i32(bytes, 12 + lump * 8);
    ASSERT_GT(length, 8u);
    const std::vector<uint8_t> cut(bytes.begin(), bytes.begin() + offset + length / 2);
    expect_mentions(parse_error(cut), {"maps/tiny.bsp", name, "outside the file"});
  }
  // A lump length that is not a whole number of records.
  auto odd = bytes;
  const int32_t planes_length = read_i32(odd, 12 + 2 * 8) - 4;
  std::memcpy(&odd[12 + 2 * 8], &planes_length, 4);
  expect_mentions(parse_error(odd), {"planes", "multiple"});
}

TEST(Q3BspFile, OutOfRangeIndicesNameTheLumpAndField) {
  const auto map = make_test_map();
  {
    auto b = map.bsp;
    b.faces[0].texture = 99;
    expect_mentions(parse_error(b), {"maps/tiny.bsp: faces", "record 0", "texture", "99"});
  }
  {
    auto b = map.bsp;
    b.mesh_verts[1] = 40;  // beyond the face's vertex range
    expect_mentions(parse_error(b), {"faces", "mesh vertex", "40"});
  }
  {
    auto b = map.bsp;
    b.faces[map.floor_face].first_vertex = 100000;
    expect_mentions(parse_error(b), {"faces", "vertices"});
  }
  {
    auto b = map.bsp;
    b.faces[map.floor_face].lightmap = 3;
    expect_mentions(parse_error(b), {"faces", "lightmap"});
  }
  {
    auto b = map.bsp;
    b.nodes[0].children[1] = -7;
    expect_mentions(parse_error(b), {"nodes", "child leaf"});
  }
  {
    auto b = map.bsp;
    b.leaf_brushes[2] = 6;
    expect_mentions(parse_error(b), {"leafbrushes", "brush"});
  }
  {
    auto b = map.bsp;
    b.brush_sides[5].plane = -1;
    expect_mentions(parse_error(b), {"brushsides", "plane"});
  }
  {
    auto b = map.bsp;
    b.models[0].face_count += 1;
    expect_mentions(parse_error(b), {"models", "faces"});
  }
  {
    auto b = map.bsp;
    b.leafs[0].cluster = 5;  // the visibility data has one cluster
    expect_mentions(parse_error(b), {"leafs", "cluster"});
  }
  {
    auto b = map.bsp;
    b.faces[map.patch_face].patch_size = {4, 3};
    expect_mentions(parse_error(b), {"faces", "patch of 4x3"});
  }
  {
    auto b = map.bsp;
    b.faces[map.patch_face].vertex_count = 8;
    expect_mentions(parse_error(b), {"faces", "patch"});
  }
  {
    auto b = map.bsp;
    b.faces[0].type = static_cast<FaceType>(9);
    expect_mentions(parse_error(b), {"faces", "unknown surface type 9"});
  }
  {
    auto b = map.bsp;
    b.vis.bytes_per_cluster = 0;
    expect_mentions(parse_error(b), {"visdata"});
  }
}

TEST(Q3BspFile, NodesMustFormATree) {
  auto b = make_test_map().bsp;
  b.planes.push_back({{1, 0, 0}, 0});
  // Node 1 is its own child: a cycle the trace would follow forever.
  b.nodes[0].children[0] = 1;
  b.nodes.push_back({static_cast<int>(b.planes.size()) - 1, {1, -1}, {}, {}});
  expect_mentions(parse_error(b), {"nodes", "reached twice"});
  b.nodes.clear();
  expect_mentions(parse_error(b), {"nodes", "empty"});
}

TEST(Q3BspFile, NonFinitePositionsFailAndNonFiniteCoordinatesAreCounted) {
  auto b = make_test_map().bsp;
  b.vertices[3].position.y = std::numeric_limits<float>::quiet_NaN();
  expect_mentions(parse_error(b), {"vertices", "record 3", "non-finite"});

  auto c = make_test_map().bsp;
  c.vertices[2].lightmap_uv.x = std::numeric_limits<float>::infinity();
  c.vertices[4].uv.y = std::numeric_limits<float>::quiet_NaN();
  const BspFile parsed = parse_bsp(write_bsp(c), "maps/tiny.bsp");
  EXPECT_EQ(parsed.non_finite_coordinates, 2);
  EXPECT_EQ(parsed.vertices[2].lightmap_uv.x, 0.0f);
  EXPECT_EQ(parsed.vertices[4].uv.y, 0.0f);

  auto d = make_test_map().bsp;
  d.planes[0].dist = std::numeric_limits<float>::infinity();
  expect_mentions(parse_error(d), {"planes", "non-finite"});
}

}  // namespace
}  // namespace cgsr::q3
