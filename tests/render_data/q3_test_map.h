#pragma once
// A tiny Quake III level built by the tests themselves (no game data needed): a closed room with
// solid brushes, polygon walls and floor, a sky ceiling, one vertex-lit triangle mesh, one Bezier
// patch, skipped surfaces (billboard, caulk, blended glass), one lightmap, spawn points and items,
// packed with its textures and a shader script into a pk3 written with libzip.
//
// Quake space: the room spans x, y in [-256, 256] and z in [0, 256].

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "render_data/q3/bsp_file.h"

namespace cgsr::q3::testing {

// Exact equality of vectors, for checks (the vector type has no operator==).
inline bool same(Vec3 a, Vec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

// The BSP writer, the inverse of parse_bsp (tests only): lumps in directory order.
std::vector<uint8_t> write_bsp(const BspFile& bsp);

struct TestMap {
  BspFile bsp;  // the level as records; write_bsp(bsp) gives the file
  // Indices of interesting faces in bsp.faces.
  int floor_face = -1, patch_face = -1, mesh_face = -1, sky_face = -1, billboard_face = -1, caulk_face = -1,
      glass_face = -1, grate_face = -1;
  // Colours baked into the fixture, for checks.
  std::array<uint8_t, 3> floor_texel{}, lightmap_texel{}, mesh_vertex_color{};
};

TestMap make_test_map();

// Uncompressed true-colour TGA (24 or 32 bits); `top_down` sets the descriptor's origin bit.
// `rgba` has width*height*channels bytes, rows top to bottom.
std::vector<uint8_t> encode_tga(int width, int height, int channels, const std::vector<uint8_t>& rgba,
                                bool top_down);

// Writes a pk3 (zip) at `path` holding `files` (name -> bytes).
void write_pk3(const std::filesystem::path& path, const std::map<std::string, std::vector<uint8_t>>& files);

// The files of the test game: maps/tiny.bsp, its textures and scripts/tiny.shader.
std::map<std::string, std::vector<uint8_t>> test_map_files(const TestMap& map);

// A fresh temporary directory, removed by the destructor.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace cgsr::q3::testing
