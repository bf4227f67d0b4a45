#include "render_data/q3/bsp_file.h"

#include <cmath>
#include <cstring>

#include "core/error.h"

namespace cgsr::q3 {
namespace {

constexpr size_t kHeaderBytes = 8 + kLumpCount * 8;
constexpr int kMaxPatchSide = 65;  // the game's MAX_GRID_SIZE

// Record sizes in bytes, per lump (0: a byte stream).
constexpr size_t kRecordBytes[kLumpCount] = {0, 72, 16, 36, 48, 4, 4, 40, 12, 8, 44, 4, 72, 104, 128 * 128 * 3, 8, 0};

struct Span {
  const uint8_t* data = nullptr;
  size_t size = 0;
};

// Reads little-endian fields of one lump; the caller has checked the lump's bounds.
class Reader {
 public:
  Reader(Span span, std::string context) : span_(span), context_(std::move(context)) {}

  size_t count(Lump lump) const { return span_.size / kRecordBytes[static_cast<int>(lump)]; }
  int32_t i32(size_t offset) const {
    uint32_t v = 0;
    for (int b = 3; b >= 0; --b) v = (v << 8) | span_.data[offset + b];
    return static_cast<int32_t>(v);
  }
  float f32(size_t offset, size_t record) const {
    const uint32_t bits = static_cast<uint32_t>(i32(offset));
    float v;
    std::memcpy(&v, &bits, sizeof v);
    if (!std::isfinite(v)) fail(record, "holds a non-finite number");
    return v;
  }
  // Texture coordinates: q3map leaves NaN lightmap coordinates on some vertex-lit surfaces, which
  // the game never reads. They become 0 and are counted instead of rejecting the map.
  float f32_or_zero(size_t offset, int& replaced) const {
    const uint32_t bits = static_cast<uint32_t>(i32(offset));
    float v;
    std::memcpy(&v, &bits, sizeof v);
    if (std::isfinite(v)) return v;
    ++replaced;
    return 0.0f;
  }
  Vec3 vec3(size_t offset, size_t record) const {
    return {f32(offset, record), f32(offset + 4, record), f32(offset + 8, record)};
  }
  std::array<int, 3> ivec3(size_t offset) const { return {i32(offset), i32(offset + 4), i32(offset + 8)}; }
  uint8_t u8(size_t offset) const { return span_.data[offset]; }
  // A NUL-padded fixed-size name.
  std::string name(size_t offset, size_t bytes) const {
    const char* p = reinterpret_cast<const char*>(span_.data + offset);
    return std::string(p, strnlen(p, bytes));
  }
  [[noreturn]] void fail(size_t record, const std::string& what) const {
    throw Error(context_, "record " + std::to_string(record) + " " + what);
  }
  const Span& span() const { return span_; }
  const std::string& context() const { return context_; }

 private:
  Span span_;
  std::string context_;
};

// Index checks: "record 12 field 'texture' = 99 is out of range [0, 40)".
void check_index(const Reader& r, size_t record, const char* field, int64_t value, int64_t lo, int64_t hi) {
  if (value < lo || value >= hi)
    r.fail(record, "field '" + std::string(field) + "' = " + std::to_string(value) + " is out of range [" +
                       std::to_string(lo) + ", " + std::to_string(hi) + ")");
}
void check_range(const Reader& r, size_t record, const char* what, int64_t first, int64_t count, size_t size) {
  if (first < 0 || count < 0 || first + count > static_cast<int64_t>(size))
    r.fail(record, std::string(what) + " [" + std::to_string(first) + ", +" + std::to_string(count) +
                       ") is out of range of " + std::to_string(size));
}

}  // namespace

const char* lump_name(Lump lump) {
  static const char* names[kLumpCount] = {"entities",    "textures", "planes",     "nodes",     "leafs",
                                          "leaffaces",   "leafbrushes", "models",  "brushes",   "brushsides",
                                          "vertices",    "meshverts", "effects",   "faces",     "lightmaps",
                                          "lightvols",   "visdata"};
  return names[static_cast<int>(lump)];
}

bool BspVisData::visible(int from, int to) const {
  if (cluster_count == 0 || from < 0 || to < 0) return true;
  return (bits[static_cast<size_t>(from) * bytes_per_cluster + (to >> 3)] >> (to & 7)) & 1;
}

namespace {
// The file's lumps: the header checked (magic, version) and every lump inside the file and a
// whole number of records.
struct Lumps {
  Span spans[kLumpCount];
  std::string name;
  Reader reader(Lump lump) const { return Reader(spans[static_cast<int>(lump)], name + ": " + lump_name(lump)); }
};

Lumps read_lump_directory(const uint8_t* data, size_t size, const std::string& name) {
  Lumps lumps;
  lumps.name = name;
  if (size < kHeaderBytes)
    throw Error(name + ": header", "file of " + std::to_string(size) + " bytes is shorter than the " +
                                       std::to_string(kHeaderBytes) + "-byte BSP header");
  const Reader header({data, size}, name + ": header");
  if (std::memcmp(data, "IBSP", 4) != 0) throw Error(name + ": header", "wrong magic (not an IBSP file)");
  const int version = header.i32(4);
  if (version != kBspVersion)
    throw Error(name + ": header", "version " + std::to_string(version) + " is not Quake III's " +
                                       std::to_string(kBspVersion));

  // Lump directory.
  for (int i = 0; i < kLumpCount; ++i) {
    const Lump lump = static_cast<Lump>(i);
    const std::string context = name + ": " + lump_name(lump);
    const int64_t offset = header.i32(8 + i * 8), length = header.i32(12 + i * 8);
    if (offset < 0 || length < 0 || offset + length > static_cast<int64_t>(size))
      throw Error(context, "lump [" + std::to_string(offset) + ", +" + std::to_string(length) +
                               ") lies outside the file of " + std::to_string(size) + " bytes (truncated?)");
    if (kRecordBytes[i] && length % static_cast<int64_t>(kRecordBytes[i]) != 0)
      throw Error(context, "length " + std::to_string(length) + " is not a multiple of the " +
                               std::to_string(kRecordBytes[i]) + "-byte record");
    lumps.spans[i] = {data + offset, static_cast<size_t>(length)};
  }
  return lumps;
}

// The tables of plain records: entities, textures, planes, the tree, models, brushes, vertices, effects.
void read_tables(const Lumps& lumps, BspFile& bsp) {
  {  // entities: text, NUL-terminated or not
    const Span& s = lumps.spans[static_cast<int>(Lump::Entities)];
    const char* text = reinterpret_cast<const char*>(s.data);
    bsp.entities.assign(text, strnlen(text, s.size));
  }
  {
    const Reader r = lumps.reader(Lump::Textures);
    for (size_t i = 0; i < r.count(Lump::Textures); ++i) {
      const size_t o = i * 72;
      bsp.textures.push_back({r.name(o, 64), r.i32(o + 64), r.i32(o + 68)});
    }
  }
  {
    const Reader r = lumps.reader(Lump::Planes);
    for (size_t i = 0; i < r.count(Lump::Planes); ++i) bsp.planes.push_back({r.vec3(i * 16, i), r.f32(i * 16 + 12, i)});
  }
  {
    const Reader r = lumps.reader(Lump::Nodes);
    for (size_t i = 0; i < r.count(Lump::Nodes); ++i) {
      const size_t o = i * 36;
      bsp.nodes.push_back({r.i32(o), {r.i32(o + 4), r.i32(o + 8)}, r.ivec3(o + 12), r.ivec3(o + 24)});
    }
  }
  {
    const Reader r = lumps.reader(Lump::Leafs);
    for (size_t i = 0; i < r.count(Lump::Leafs); ++i) {
      const size_t o = i * 48;
      bsp.leafs.push_back({r.i32(o), r.i32(o + 4), r.ivec3(o + 8), r.ivec3(o + 20), r.i32(o + 32), r.i32(o + 36),
                           r.i32(o + 40), r.i32(o + 44)});
    }
  }
  for (Lump lump : {Lump::LeafFaces, Lump::LeafBrushes, Lump::MeshVerts}) {
    const Reader r = lumps.reader(lump);
    auto& out = lump == Lump::LeafFaces ? bsp.leaf_faces : lump == Lump::LeafBrushes ? bsp.leaf_brushes : bsp.mesh_verts;
    for (size_t i = 0; i < r.count(lump); ++i) out.push_back(r.i32(i * 4));
  }
  {
    const Reader r = lumps.reader(Lump::Models);
    for (size_t i = 0; i < r.count(Lump::Models); ++i) {
      const size_t o = i * 40;
      bsp.models.push_back({r.vec3(o, i), r.vec3(o + 12, i), r.i32(o + 24), r.i32(o + 28), r.i32(o + 32), r.i32(o + 36)});
    }
  }
  {
    const Reader r = lumps.reader(Lump::Brushes);
    for (size_t i = 0; i < r.count(Lump::Brushes); ++i)
      bsp.brushes.push_back({r.i32(i * 12), r.i32(i * 12 + 4), r.i32(i * 12 + 8)});
  }
  {
    const Reader r = lumps.reader(Lump::BrushSides);
    for (size_t i = 0; i < r.count(Lump::BrushSides); ++i) bsp.brush_sides.push_back({r.i32(i * 8), r.i32(i * 8 + 4)});
  }
  {
    const Reader r = lumps.reader(Lump::Vertices);
    bsp.vertices.reserve(r.count(Lump::Vertices));
    for (size_t i = 0; i < r.count(Lump::Vertices); ++i) {
      const size_t o = i * 44;
      BspVertex v;
      v.position = r.vec3(o, i);
      int& bad = bsp.non_finite_coordinates;
      v.uv = {r.f32_or_zero(o + 12, bad), r.f32_or_zero(o + 16, bad)};
      v.lightmap_uv = {r.f32_or_zero(o + 20, bad), r.f32_or_zero(o + 24, bad)};
      v.normal = r.vec3(o + 28, i);
      for (int c = 0; c < 4; ++c) v.color[c] = r.u8(o + 40 + c);
      bsp.vertices.push_back(v);
    }
  }
  {
    const Reader r = lumps.reader(Lump::Effects);
    for (size_t i = 0; i < r.count(Lump::Effects); ++i)
      bsp.effects.push_back({r.name(i * 72, 64), r.i32(i * 72 + 64), r.i32(i * 72 + 68)});
  }
}

// The faces, with their surface type checked.
void read_faces(const Lumps& lumps, BspFile& bsp) {
  {
    const Reader r = lumps.reader(Lump::Faces);
    bsp.faces.reserve(r.count(Lump::Faces));
    for (size_t i = 0; i < r.count(Lump::Faces); ++i) {
      const size_t o = i * 104;
      BspFace f;
      f.texture = r.i32(o);
      f.effect = r.i32(o + 4);
      const int type = r.i32(o + 8);
      if (type < 1 || type > 4) r.fail(i, "has unknown surface type " + std::to_string(type));
      f.type = static_cast<FaceType>(type);
      f.first_vertex = r.i32(o + 12);
      f.vertex_count = r.i32(o + 16);
      f.first_mesh_vert = r.i32(o + 20);
      f.mesh_vert_count = r.i32(o + 24);
      f.lightmap = r.i32(o + 28);
      f.lightmap_start = {r.i32(o + 32), r.i32(o + 36)};
      f.lightmap_size = {r.i32(o + 40), r.i32(o + 44)};
      f.lightmap_origin = r.vec3(o + 48, i);
      f.lightmap_vecs = {r.vec3(o + 60, i), r.vec3(o + 72, i)};
      f.normal = r.vec3(o + 84, i);
      f.patch_size = {r.i32(o + 96), r.i32(o + 100)};
      bsp.faces.push_back(f);
    }
  }
}

// Lightmaps, the light volume grid and the visibility data (its header checked against the lump).
void read_lighting_and_vis(const Lumps& lumps, BspFile& bsp) {
  {
    const Reader r = lumps.reader(Lump::Lightmaps);
    for (size_t i = 0; i < r.count(Lump::Lightmaps); ++i) {
      const uint8_t* p = r.span().data + i * kRecordBytes[static_cast<int>(Lump::Lightmaps)];
      bsp.lightmaps.push_back({std::vector<uint8_t>(p, p + kRecordBytes[static_cast<int>(Lump::Lightmaps)])});
    }
  }
  {
    const Reader r = lumps.reader(Lump::LightVols);
    for (size_t i = 0; i < r.count(Lump::LightVols); ++i) {
      const size_t o = i * 8;
      bsp.light_volumes.push_back(
          {{r.u8(o), r.u8(o + 1), r.u8(o + 2)}, {r.u8(o + 3), r.u8(o + 4), r.u8(o + 5)}, {r.u8(o + 6), r.u8(o + 7)}});
    }
  }
  {
    const Reader r = lumps.reader(Lump::VisData);
    const Span& s = r.span();
    if (s.size > 0) {
      if (s.size < 8) throw Error(r.context(), "lump of " + std::to_string(s.size) + " bytes has no 8-byte header");
      const int64_t clusters = r.i32(0), bytes = r.i32(4);
      if (clusters < 0 || bytes < 0 || (clusters > 0 && bytes < (clusters + 7) / 8) ||
          8 + clusters * bytes > static_cast<int64_t>(s.size))
        throw Error(r.context(), std::to_string(clusters) + " clusters of " + std::to_string(bytes) +
                                     " bytes do not fit the lump of " + std::to_string(s.size) + " bytes");
      bsp.vis.cluster_count = static_cast<int>(clusters);
      bsp.vis.bytes_per_cluster = static_cast<int>(bytes);
      bsp.vis.bits.assign(s.data + 8, s.data + 8 + clusters * bytes);
    }
  }
}

// The nodes: indices inside their tables, and a tree below node 0 of bounded depth.
void check_node_tree(const Lumps& lumps, BspFile& bsp) {
  const int64_t n_planes = bsp.planes.size(), n_nodes = bsp.nodes.size(), n_leafs = bsp.leafs.size();
  {
    const Reader r = lumps.reader(Lump::Nodes);
    if (n_nodes == 0) throw Error(r.context(), "lump is empty: a map needs at least one node");
    for (size_t i = 0; i < bsp.nodes.size(); ++i) {
      const BspNode& n = bsp.nodes[i];
      check_index(r, i, "plane", n.plane, 0, n_planes);
      for (int c : n.children) {
        if (c >= 0) check_index(r, i, "child node", c, 1, n_nodes);  // the root (0) is nobody's child
        else check_index(r, i, "child leaf", -static_cast<int64_t>(c) - 1, 0, n_leafs);
      }
    }
    // The nodes must form a tree below node 0: no node reached twice, depth bounded (the
    // trace recurses along it).
    std::vector<char> seen(bsp.nodes.size(), 0);
    std::vector<std::pair<int, int>> stack{{0, 1}};
    seen[0] = 1;
    while (!stack.empty()) {
      const auto [node, depth] = stack.back();
      stack.pop_back();
      bsp.tree_depth = std::max(bsp.tree_depth, depth);
      if (depth > kMaxTreeDepth)
        throw Error(r.context(), "node tree is deeper than " + std::to_string(kMaxTreeDepth));
      for (int c : bsp.nodes[node].children) {
        if (c < 0) continue;
        if (seen[c]) r.fail(c, "is reached twice from the root: the nodes do not form a tree");
        seen[c] = 1;
        stack.push_back({c, depth + 1});
      }
    }
  }
}

// Every other record's indices land inside their tables.
void check_table_references(const Lumps& lumps, const BspFile& bsp) {
  const int64_t n_textures = bsp.textures.size(), n_planes = bsp.planes.size(), n_faces = bsp.faces.size(),
                n_brushes = bsp.brushes.size();
  {
    const Reader r = lumps.reader(Lump::Leafs);
    for (size_t i = 0; i < bsp.leafs.size(); ++i) {
      const BspLeaf& l = bsp.leafs[i];
      check_range(r, i, "leaf faces", l.first_leaf_face, l.leaf_face_count, bsp.leaf_faces.size());
      check_range(r, i, "leaf brushes", l.first_leaf_brush, l.leaf_brush_count, bsp.leaf_brushes.size());
      if (bsp.vis.cluster_count > 0) check_index(r, i, "cluster", l.cluster, -1, bsp.vis.cluster_count);
    }
  }
  {
    const Reader r = lumps.reader(Lump::LeafFaces);
    for (size_t i = 0; i < bsp.leaf_faces.size(); ++i) check_index(r, i, "face", bsp.leaf_faces[i], 0, n_faces);
  }
  {
    const Reader r = lumps.reader(Lump::LeafBrushes);
    for (size_t i = 0; i < bsp.leaf_brushes.size(); ++i) check_index(r, i, "brush", bsp.leaf_brushes[i], 0, n_brushes);
  }
  {
    const Reader r = lumps.reader(Lump::Models);
    if (bsp.models.empty()) throw Error(r.context(), "lump is empty: the world model is missing");
    for (size_t i = 0; i < bsp.models.size(); ++i) {
      check_range(r, i, "faces", bsp.models[i].first_face, bsp.models[i].face_count, bsp.faces.size());
      check_range(r, i, "brushes", bsp.models[i].first_brush, bsp.models[i].brush_count, bsp.brushes.size());
    }
  }
  {
    const Reader r = lumps.reader(Lump::Brushes);
    for (size_t i = 0; i < bsp.brushes.size(); ++i) {
      check_range(r, i, "sides", bsp.brushes[i].first_side, bsp.brushes[i].side_count, bsp.brush_sides.size());
      check_index(r, i, "texture", bsp.brushes[i].texture, 0, n_textures);
    }
  }
  {
    const Reader r = lumps.reader(Lump::BrushSides);
    for (size_t i = 0; i < bsp.brush_sides.size(); ++i) {
      check_index(r, i, "plane", bsp.brush_sides[i].plane, 0, n_planes);
      check_index(r, i, "texture", bsp.brush_sides[i].texture, 0, n_textures);
    }
  }
  {
    const Reader r = lumps.reader(Lump::Effects);
    for (size_t i = 0; i < bsp.effects.size(); ++i) {
      check_index(r, i, "brush", bsp.effects[i].brush, -1, n_brushes);
    }
  }
}

// Each face's indices, and its mesh or patch consistent with its type.
void check_face_references(const Lumps& lumps, const BspFile& bsp) {
  const int64_t n_textures = bsp.textures.size(), n_effects = bsp.effects.size(), n_lightmaps = bsp.lightmaps.size();
  {
    const Reader r = lumps.reader(Lump::Faces);
    for (size_t i = 0; i < bsp.faces.size(); ++i) {
      const BspFace& f = bsp.faces[i];
      check_index(r, i, "texture", f.texture, 0, n_textures);
      check_index(r, i, "effect", f.effect, -1, n_effects);
      check_range(r, i, "vertices", f.first_vertex, f.vertex_count, bsp.vertices.size());
      if (f.lightmap >= 0) check_index(r, i, "lightmap", f.lightmap, 0, n_lightmaps);
      switch (f.type) {
        case FaceType::Polygon:
        case FaceType::Mesh:
          check_range(r, i, "mesh vertices", f.first_mesh_vert, f.mesh_vert_count, bsp.mesh_verts.size());
          if (f.mesh_vert_count % 3 != 0)
            r.fail(i, "has " + std::to_string(f.mesh_vert_count) + " mesh vertices, not a whole number of triangles");
          for (int k = 0; k < f.mesh_vert_count; ++k)
            check_index(r, i, "mesh vertex", bsp.mesh_verts[f.first_mesh_vert + k], 0, f.vertex_count);
          break;
        case FaceType::Patch: {
          const int w = f.patch_size[0], h = f.patch_size[1];
          if (w < 3 || h < 3 || w % 2 == 0 || h % 2 == 0 || w > kMaxPatchSide || h > kMaxPatchSide)
            r.fail(i, "is a patch of " + std::to_string(w) + "x" + std::to_string(h) +
                          " control points; sides must be odd and in [3, " + std::to_string(kMaxPatchSide) + "]");
          if (w * h != f.vertex_count)
            r.fail(i, "is a " + std::to_string(w) + "x" + std::to_string(h) + " patch with " +
                          std::to_string(f.vertex_count) + " control points");
          break;
        }
        case FaceType::Billboard:
          break;
      }
    }
  }
}
}  // namespace

BspFile parse_bsp(const uint8_t* data, size_t size, const std::string& name) {
  const Lumps lumps = read_lump_directory(data, size, name);
  BspFile bsp;
  bsp.name = name;
  read_tables(lumps, bsp);
  read_faces(lumps, bsp);
  read_lighting_and_vis(lumps, bsp);
  // Cross-references: every index lands inside its table.
  check_node_tree(lumps, bsp);
  check_table_references(lumps, bsp);
  check_face_references(lumps, bsp);
  return bsp;
}

}  // namespace cgsr::q3
