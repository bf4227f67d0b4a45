#pragma once
// Quake III Arena BSP files ("IBSP", version 46), as written by q3map: a header with 17 lump
// directory entries (offset, length) followed by the lumps. parse_bsp reads every lump into
// plain records and validates all of it (lump bounds, record sizes, every index, finite positions,
// normals and planes, an acyclic node tree), so code that walks the result needs no bounds checks.
// A bad file gives cgsr::Error("<file>: <lump>", what), never a crash.
//
// Positions are in Quake's space: right-handed, Z up, game units (a player stands 56 units tall).
// All lumps are little-endian; records are read field by field, never cast from the buffer.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "render_data/vec_math.h"

namespace cgsr::q3 {

enum class Lump : int {
  Entities = 0, Textures, Planes, Nodes, Leafs, LeafFaces, LeafBrushes, Models, Brushes, BrushSides,
  Vertices, MeshVerts, Effects, Faces, Lightmaps, LightVols, VisData,
};
constexpr int kLumpCount = 17;
const char* lump_name(Lump lump);  // "faces", "lightmaps", ...

// Surface flags and content flags the loader looks at (q3map copies them from the shaders).
namespace surface_flags {
constexpr int kSky = 0x4;
constexpr int kNoDraw = 0x80;
constexpr int kHint = 0x100;
constexpr int kSkip = 0x200;
constexpr int kNoLightmap = 0x400;
}  // namespace surface_flags
namespace contents {
constexpr int kSolid = 0x1;
constexpr int kLava = 0x8;
constexpr int kSlime = 0x10;
constexpr int kWater = 0x20;
constexpr int kFog = 0x40;
constexpr int kPlayerClip = 0x10000;
constexpr int kTrigger = 0x40000000;
constexpr int kTranslucent = 0x20000000;
}  // namespace contents

enum class FaceType : int { Polygon = 1, Patch = 2, Mesh = 3, Billboard = 4 };

struct BspTexture {  // a shader reference: "textures/base_wall/metalfloor_wall_15"
  std::string name;
  int surface_flags = 0;
  int contents = 0;
};

struct BspPlane {
  Vec3 normal;
  float dist = 0;
};

struct BspNode {
  int plane = 0;
  std::array<int, 2> children{};  // >= 0: node index; < 0: leaf index -(child + 1). [0] is in front
  std::array<int, 3> mins{}, maxs{};
};

struct BspLeaf {
  int cluster = -1;  // -1: outside the playable space (or opaque)
  int area = 0;
  std::array<int, 3> mins{}, maxs{};
  int first_leaf_face = 0, leaf_face_count = 0;
  int first_leaf_brush = 0, leaf_brush_count = 0;
};

struct BspModel {  // model 0 is the world; the others are doors, platforms, triggers
  Vec3 mins, maxs;
  int first_face = 0, face_count = 0;
  int first_brush = 0, brush_count = 0;
};

struct BspBrush {
  int first_side = 0, side_count = 0;
  int texture = 0;  // its contents say whether it blocks
};

struct BspBrushSide {
  int plane = 0;
  int texture = 0;
};

struct BspVertex {
  Vec3 position;
  Vec2 uv;           // texture coordinates (1 = one repetition of the texture)
  Vec2 lightmap_uv;  // in [0,1] of the face's 128x128 lightmap page
  Vec3 normal;
  std::array<uint8_t, 4> color{};  // baked vertex lighting (RGBA) for surfaces without lightmap
};

struct BspEffect {  // fog volumes
  std::string name;
  int brush = -1;
  int visible_side = -1;
};

struct BspFace {
  int texture = 0;
  int effect = -1;
  FaceType type = FaceType::Polygon;
  int first_vertex = 0, vertex_count = 0;
  int first_mesh_vert = 0, mesh_vert_count = 0;  // triangle list, indices relative to first_vertex
  int lightmap = -1;                             // < 0: no lightmap (vertex lit)
  std::array<int, 2> lightmap_start{}, lightmap_size{};
  Vec3 lightmap_origin;
  std::array<Vec3, 2> lightmap_vecs;
  Vec3 normal;
  std::array<int, 2> patch_size{};  // control points across x down, for patches
};

constexpr int kLightmapSize = 128;
struct BspLightmap {
  std::vector<uint8_t> rgb;  // 128 * 128 * 3, as stored (before the overbright shift)
};

struct BspLightVolume {
  std::array<uint8_t, 3> ambient{}, directional{};
  std::array<uint8_t, 2> direction{};  // phi, theta
};

struct BspVisData {
  int cluster_count = 0;
  int bytes_per_cluster = 0;
  std::vector<uint8_t> bits;  // cluster_count * bytes_per_cluster
  // Whether `to` is potentially visible from `from`; true when the map has no visibility data.
  bool visible(int from, int to) const;
};

struct BspFile {
  std::string name;  // for messages
  std::string entities;
  std::vector<BspTexture> textures;
  std::vector<BspPlane> planes;
  std::vector<BspNode> nodes;
  std::vector<BspLeaf> leafs;
  std::vector<int> leaf_faces, leaf_brushes;
  std::vector<BspModel> models;
  std::vector<BspBrush> brushes;
  std::vector<BspBrushSide> brush_sides;
  std::vector<BspVertex> vertices;
  std::vector<int> mesh_verts;
  std::vector<BspEffect> effects;
  std::vector<BspFace> faces;
  std::vector<BspLightmap> lightmaps;
  std::vector<BspLightVolume> light_volumes;
  BspVisData vis;
  int non_finite_coordinates = 0;  // vertex uv / lightmap uv values that were NaN or Inf, set to 0
  int tree_depth = 0;  // deepest node chain from the root; bounded by parse_bsp
};

constexpr int kBspVersion = 46;
constexpr int kMaxTreeDepth = 2048;

// Parses and validates a whole BSP. `name` is used in every error ("maps/x.bsp: faces").
BspFile parse_bsp(const uint8_t* data, size_t size, const std::string& name);
inline BspFile parse_bsp(const std::vector<uint8_t>& bytes, const std::string& name) {
  return parse_bsp(bytes.data(), bytes.size(), name);
}

}  // namespace cgsr::q3
