#include "tests/render_data/q3_test_map.h"

#include <unistd.h>
#include <zip.h>

#include <cstring>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <stdexcept>

namespace cgsr::q3::testing {
namespace {

class Bytes {
 public:
  void i32(int32_t v) { raw(&v, 4); }
  void f32(float v) { raw(&v, 4); }
  void vec3(Vec3 v) { f32(v.x), f32(v.y), f32(v.z); }
  void u8(uint8_t v) { data.push_back(v); }
  void name(const std::string& s, size_t width) {
    std::vector<uint8_t> field(width, 0);
    std::memcpy(field.data(), s.data(), std::min(s.size(), width));
    data.insert(data.end(), field.begin(), field.end());
  }
  void raw(const void* p, size_t n) {
    const auto* b = static_cast<const uint8_t*>(p);
    data.insert(data.end(), b, b + n);  // the test machine is little-endian, like the format
  }
  std::vector<uint8_t> data;
};

BspVertex vertex(Vec3 position, Vec2 uv, Vec2 lightmap_uv, Vec3 normal, std::array<uint8_t, 4> color = {255, 255, 255, 255}) {
  BspVertex v;
  v.position = position;
  v.uv = uv;
  v.lightmap_uv = lightmap_uv;
  v.normal = normal;
  v.color = color;
  return v;
}

struct Builder {
  BspFile bsp;

  int texture(const std::string& name, int flags, int contents) {
    bsp.textures.push_back({name, flags, contents});
    return static_cast<int>(bsp.textures.size()) - 1;
  }
  int plane(Vec3 normal, float dist) {
    bsp.planes.push_back({normal, dist});
    return static_cast<int>(bsp.planes.size()) - 1;
  }
  void box_brush(Vec3 lo, Vec3 hi, int texture) {
    const int first = static_cast<int>(bsp.brush_sides.size());
    for (int axis = 0; axis < 3; ++axis) {
      Vec3 n{};
      n[axis] = 1;
      bsp.brush_sides.push_back({plane(n, hi[axis]), texture});
      n[axis] = -1;
      bsp.brush_sides.push_back({plane(n, -lo[axis]), texture});
    }
    bsp.brushes.push_back({first, 6, texture});
  }
  // A convex polygon, vertices clockwise seen from the front, triangulated as a fan.
  int polygon(int texture, const std::vector<BspVertex>& vertices, Vec3 normal, int lightmap,
              FaceType type = FaceType::Polygon) {
    BspFace f;
    f.texture = texture;
    f.type = type;
    f.first_vertex = static_cast<int>(bsp.vertices.size());
    f.vertex_count = static_cast<int>(vertices.size());
    f.first_mesh_vert = static_cast<int>(bsp.mesh_verts.size());
    for (size_t k = 1; k + 1 < vertices.size(); ++k)
      bsp.mesh_verts.insert(bsp.mesh_verts.end(), {0, static_cast<int>(k), static_cast<int>(k + 1)});
    f.mesh_vert_count = static_cast<int>(bsp.mesh_verts.size()) - f.first_mesh_vert;
    f.lightmap = lightmap;
    f.lightmap_size = {lightmap >= 0 ? 16 : 0, lightmap >= 0 ? 16 : 0};
    f.normal = normal;
    bsp.vertices.insert(bsp.vertices.end(), vertices.begin(), vertices.end());
    bsp.faces.push_back(f);
    return static_cast<int>(bsp.faces.size()) - 1;
  }
  // An axis-aligned rectangle facing +normal (one of +-x, +-y, +-z) at `offset` along it.
  int rectangle(int texture, int axis, float sign, float offset, float a0, float a1, float b0, float b1, int lightmap) {
    const int ua = (axis + 1) % 3, ub = (axis + 2) % 3;
    auto point = [&](float a, float b) {
      Vec3 p{};
      p[axis] = offset;
      p[ua] = a;
      p[ub] = b;
      return p;
    };
    Vec3 normal{};
    normal[axis] = sign;
    // (ua, ub, axis) is right-handed: counter-clockwise around +axis is a0b0, a1b0, a1b1, a0b1.
    std::vector<Vec3> corners = {point(a0, b0), point(a1, b0), point(a1, b1), point(a0, b1)};
    if (sign > 0) std::reverse(corners.begin(), corners.end());  // clockwise seen from the front
    std::vector<BspVertex> vs;
    for (const Vec3& c : corners)
      vs.push_back(vertex(c, {c[ua] / 128.0f, -c[ub] / 128.0f},
                          {(c[ua] - a0) / (a1 - a0) * 0.9f + 0.05f, (c[ub] - b0) / (b1 - b0) * 0.9f + 0.05f}, normal));
    return polygon(texture, vs, normal, lightmap);
  }
};

std::string entity_text() {
  return "{\n\"classname\" \"worldspawn\"\n\"message\" \"tiny\"\n}\n"
         "{\n\"classname\" \"info_player_deathmatch\"\n\"origin\" \"-128 -128 24\"\n\"angle\" \"45\"\n}\n"
         "{\n\"classname\" \"info_player_deathmatch\"\n\"origin\" \"128 -160 24\"\n}\n"
         "{\n\"classname\" \"item_health\"\n\"origin\" \"-128 128 16\"\n}\n"
         "{\n\"classname\" \"weapon_shotgun\"\n\"origin\" \"0 160 16\"\n}\n"
         "// a comment the game's parser skips\n"
         "{\n\"classname\" \"light\"\n\"origin\" \"0 0 200\"\n\"light\" \"300\"\n}\n";
}

std::vector<uint8_t> uniform_rgb(int width, int height, std::array<uint8_t, 3> c) {
  std::vector<uint8_t> out(static_cast<size_t>(width) * height * 3);
  for (size_t i = 0; i < out.size(); ++i) out[i] = c[i % 3];
  return out;
}

}  // namespace

std::vector<uint8_t> write_bsp(const BspFile& bsp) {
  Bytes lumps[kLumpCount];
  lumps[0].raw(bsp.entities.data(), bsp.entities.size());
  lumps[0].u8(0);
  for (const auto& t : bsp.textures) lumps[1].name(t.name, 64), lumps[1].i32(t.surface_flags), lumps[1].i32(t.contents);
  for (const auto& p : bsp.planes) lumps[2].vec3(p.normal), lumps[2].f32(p.dist);
  for (const auto& n : bsp.nodes) {
    lumps[3].i32(n.plane);
    for (int c : n.children) lumps[3].i32(c);
    for (int v : n.mins) lumps[3].i32(v);
    for (int v : n.maxs) lumps[3].i32(v);
  }
  for (const auto& l : bsp.leafs) {
    Bytes& b = lumps[4];
    b.i32(l.cluster), b.i32(l.area);
    for (int v : l.mins) b.i32(v);
    for (int v : l.maxs) b.i32(v);
    b.i32(l.first_leaf_face), b.i32(l.leaf_face_count), b.i32(l.first_leaf_brush), b.i32(l.leaf_brush_count);
  }
  for (int v : bsp.leaf_faces) lumps[5].i32(v);
  for (int v : bsp.leaf_brushes) lumps[6].i32(v);
  for (const auto& m : bsp.models) {
    Bytes& b = lumps[7];
    b.vec3(m.mins), b.vec3(m.maxs), b.i32(m.first_face), b.i32(m.face_count), b.i32(m.first_brush), b.i32(m.brush_count);
  }
  for (const auto& br : bsp.brushes) lumps[8].i32(br.first_side), lumps[8].i32(br.side_count), lumps[8].i32(br.texture);
  for (const auto& s : bsp.brush_sides) lumps[9].i32(s.plane), lumps[9].i32(s.texture);
  for (const auto& v : bsp.vertices) {
    Bytes& b = lumps[10];
    b.vec3(v.position), b.f32(v.uv.x), b.f32(v.uv.y), b.f32(v.lightmap_uv.x), b.f32(v.lightmap_uv.y), b.vec3(v.normal);
    for (uint8_t c : v.color) b.u8(c);
  }
  for (int v : bsp.mesh_verts) lumps[11].i32(v);
  for (const auto& e : bsp.effects) lumps[12].name(e.name, 64), lumps[12].i32(e.brush), lumps[12].i32(e.visible_side);
  for (const auto& f : bsp.faces) {
    Bytes& b = lumps[13];
    b.i32(f.texture), b.i32(f.effect), b.i32(static_cast<int>(f.type)), b.i32(f.first_vertex), b.i32(f.vertex_count);
    b.i32(f.first_mesh_vert), b.i32(f.mesh_vert_count), b.i32(f.lightmap);
    b.i32(f.lightmap_start[0]), b.i32(f.lightmap_start[1]), b.i32(f.lightmap_size[0]), b.i32(f.lightmap_size[1]);
    b.vec3(f.lightmap_origin), b.vec3(f.lightmap_vecs[0]), b.vec3(f.lightmap_vecs[1]), b.vec3(f.normal);
    b.i32(f.patch_size[0]), b.i32(f.patch_size[1]);
  }
  for (const auto& l : bsp.lightmaps) lumps[14].raw(l.rgb.data(), l.rgb.size());
  for (const auto& v : bsp.light_volumes) {
    for (uint8_t c : v.ambient) lumps[15].u8(c);
    for (uint8_t c : v.directional) lumps[15].u8(c);
    for (uint8_t c : v.direction) lumps[15].u8(c);
  }
  if (bsp.vis.cluster_count > 0) {
    lumps[16].i32(bsp.vis.cluster_count), lumps[16].i32(bsp.vis.bytes_per_cluster);
    lumps[16].raw(bsp.vis.bits.data(), bsp.vis.bits.size());
  }
  Bytes out;
  out.raw("IBSP", 4);
  out.i32(kBspVersion);
  int32_t offset = 8 + kLumpCount * 8;
  for (auto& lump : lumps) {
    while (lump.data.size() % 4) lump.u8(0);  // keep every lump 4-byte aligned (record sizes are)
  }
  for (const auto& lump : lumps) {
    out.i32(offset);
    out.i32(static_cast<int32_t>(lump.data.size()));
    offset += static_cast<int32_t>(lump.data.size());
  }
  for (const auto& lump : lumps) out.raw(lump.data.data(), lump.data.size());
  return out.data;
}

TestMap make_test_map() {
  TestMap map;
  Builder b;
  b.bsp.name = "maps/tiny.bsp";
  b.bsp.entities = entity_text();
  const int solid = contents::kSolid;
  const int wall = b.texture("textures/test/wall", 0, solid);
  const int floor = b.texture("textures/test/floor", 0, solid);
  const int sky = b.texture("textures/test/sky", surface_flags::kSky | surface_flags::kNoLightmap, solid);
  const int mesh = b.texture("textures/test/mesh", 0, 0);
  const int patch = b.texture("textures/test/patch", 0, solid);
  const int flare = b.texture("flareShader", 0, 0);
  const int caulk = b.texture("textures/common/caulk", surface_flags::kNoDraw, solid);
  const int glass = b.texture("textures/test/glass", 0, contents::kTranslucent);
  const int grate = b.texture("textures/test/grate", 0, solid);

  // Node 0 splits nothing useful: the room is leaf 0 (cluster 0), leaf 1 is below the world.
  const int split = b.plane({0, 0, 1}, -512);
  b.bsp.nodes.push_back({split, {-1, -2}, {-272, -272, -512}, {272, 272, 272}});

  // Solid shell: floor, ceiling (sky), four walls.
  b.box_brush({-272, -272, -16}, {272, 272, 0}, floor);
  b.box_brush({-272, -272, 256}, {272, 272, 272}, sky);
  b.box_brush({-272, -272, -16}, {-256, 272, 272}, wall);
  b.box_brush({256, -272, -16}, {272, 272, 272}, wall);
  b.box_brush({-272, -272, -16}, {272, -256, 272}, wall);
  b.box_brush({-272, 256, -16}, {272, 272, 272}, wall);

  map.floor_face = b.rectangle(floor, 2, 1, 0, -256, 256, -256, 256, 0);
  map.sky_face = b.rectangle(sky, 2, -1, 256, -256, 256, -256, 256, -1);
  b.rectangle(wall, 0, 1, -256, -256, 256, 0, 256, 0);
  b.rectangle(wall, 0, -1, 256, -256, 256, 0, 256, 0);
  b.rectangle(wall, 1, 1, -256, 0, 256, -256, 256, 0);  // axis y: (ua, ub) = (z, x)
  b.rectangle(wall, 1, -1, 256, 0, 256, -256, 256, 0);
  map.caulk_face = b.rectangle(caulk, 2, -1, -16, -256, 256, -256, 256, -1);
  map.glass_face = b.rectangle(glass, 0, -1, 255, -64, 64, 64, 160, 0);  // a window on the +x wall
  map.grate_face = b.rectangle(grate, 1, -1, 255, 64, 128, -200, -136, 0);

  // A vertex-lit pyramid (triangle mesh) at (128, 128).
  map.mesh_vertex_color = {200, 100, 50};
  {
    const std::array<uint8_t, 4> c = {200, 100, 50, 255};
    const Vec3 p[4] = {{96, 96, 0}, {160, 96, 0}, {128, 160, 0}, {128, 128, 64}};
    const Vec3 centre = (p[0] + p[1] + p[2] + p[3]) * 0.25f;
    BspFace f;
    f.texture = mesh;
    f.type = FaceType::Mesh;
    f.first_vertex = static_cast<int>(b.bsp.vertices.size());
    f.vertex_count = 4;
    f.first_mesh_vert = static_cast<int>(b.bsp.mesh_verts.size());
    f.lightmap = -3;
    for (const Vec3& q : p) b.bsp.vertices.push_back(vertex(q, {q.x / 64, q.y / 64}, {0, 0}, normalize(q - centre), c));
    const int tris[3][3] = {{0, 1, 3}, {1, 2, 3}, {2, 0, 3}};
    for (const auto& t : tris) {
      const Vec3 n = cross(p[t[1]] - p[t[0]], p[t[2]] - p[t[0]]);
      const Vec3 out = (p[t[0]] + p[t[1]] + p[t[2]]) * (1.0f / 3) - centre;
      if (dot(n, out) > 0) b.bsp.mesh_verts.insert(b.bsp.mesh_verts.end(), {t[0], t[2], t[1]});  // clockwise
      else b.bsp.mesh_verts.insert(b.bsp.mesh_verts.end(), {t[0], t[1], t[2]});
    }
    f.mesh_vert_count = 9;
    b.bsp.faces.push_back(f);
    map.mesh_face = static_cast<int>(b.bsp.faces.size()) - 1;
  }

  // A quarter pipe (3x3 Bezier patch) in the corner of the -x wall and the floor.
  {
    BspFace f;
    f.texture = patch;
    f.type = FaceType::Patch;
    f.first_vertex = static_cast<int>(b.bsp.vertices.size());
    f.vertex_count = 9;
    f.lightmap = 0;
    f.patch_size = {3, 3};
    const Vec3 n = normalize(Vec3{1, 0, 1});
    const float ys[3] = {-64, 0, 64};
    const Vec3 profile[3] = {{-256, 0, 64}, {-256, 0, 0}, {-192, 0, 0}};
    for (int row = 0; row < 3; ++row)
      for (int col = 0; col < 3; ++col) {
        const Vec3 q{profile[row].x, ys[col], profile[row].z};
        b.bsp.vertices.push_back(vertex(q, {col * 0.5f, row * 0.5f}, {0.25f + col * 0.1f, 0.25f + row * 0.1f}, n));
      }
    b.bsp.faces.push_back(f);
    map.patch_face = static_cast<int>(b.bsp.faces.size()) - 1;
  }

  // A flare (billboard): one vertex.
  {
    BspFace f;
    f.texture = flare;
    f.type = FaceType::Billboard;
    f.first_vertex = static_cast<int>(b.bsp.vertices.size());
    f.vertex_count = 1;
    b.bsp.vertices.push_back(vertex({0, 0, 200}, {0, 0}, {0, 0}, {0, 0, 1}));
    b.bsp.faces.push_back(f);
    map.billboard_face = static_cast<int>(b.bsp.faces.size()) - 1;
  }

  const int faces = static_cast<int>(b.bsp.faces.size()), brushes = static_cast<int>(b.bsp.brushes.size());
  for (int i = 0; i < faces; ++i) b.bsp.leaf_faces.push_back(i);
  for (int i = 0; i < brushes; ++i) b.bsp.leaf_brushes.push_back(i);
  b.bsp.leafs.push_back({0, 0, {-272, -272, -16}, {272, 272, 272}, 0, faces, 0, brushes});
  b.bsp.leafs.push_back({-1, 0, {-272, -272, -512}, {272, 272, -16}, 0, 0, 0, 0});
  b.bsp.models.push_back({{-272, -272, -16}, {272, 272, 272}, 0, faces, 0, brushes});
  b.bsp.effects.push_back({"textures/test/fog", 0, 5});

  map.lightmap_texel = {100, 80, 60};
  BspLightmap lm;
  lm.rgb = uniform_rgb(kLightmapSize, kLightmapSize, map.lightmap_texel);
  b.bsp.lightmaps.push_back(lm);
  b.bsp.light_volumes.push_back({{10, 20, 30}, {40, 50, 60}, {7, 8}});
  b.bsp.vis = {1, 1, {0x01}};

  map.floor_texel = {160, 120, 80};
  map.bsp = std::move(b.bsp);
  return map;
}

std::vector<uint8_t> encode_tga(int width, int height, int channels, const std::vector<uint8_t>& rgba,
                                bool top_down) {
  // Header: no id, no colour map, type 2 (uncompressed true colour), origin 0, size, depth, and
  // the descriptor (alpha bits, top-down flag).
  std::vector<uint8_t> out = {0, 0, 2, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  for (int v : {width, height}) {
    out.push_back(static_cast<uint8_t>(v & 0xFF));
    out.push_back(static_cast<uint8_t>(v >> 8));
  }
  out.push_back(static_cast<uint8_t>(channels * 8));
  out.push_back(static_cast<uint8_t>((channels == 4 ? 8 : 0) | (top_down ? 0x20 : 0)));
  for (int row = 0; row < height; ++row) {
    const int source = top_down ? row : height - 1 - row;
    for (int x = 0; x < width; ++x) {
      const uint8_t* p = &rgba[(static_cast<size_t>(source) * width + x) * channels];
      out.push_back(p[2]);  // BGR(A)
      out.push_back(p[1]);
      out.push_back(p[0]);
      if (channels == 4) out.push_back(p[3]);
    }
  }
  return out;
}

void write_pk3(const std::filesystem::path& path, const std::map<std::string, std::vector<uint8_t>>& files) {
  int code = 0;
  zip_t* zip = zip_open(path.c_str(), ZIP_CREATE | ZIP_TRUNCATE, &code);
  if (!zip) throw std::runtime_error("cannot create " + path.string());
  for (const auto& [name, bytes] : files) {
    zip_source_t* source = zip_source_buffer(zip, bytes.data(), bytes.size(), 0);  // read at close
    if (!source || zip_file_add(zip, name.c_str(), source, ZIP_FL_OVERWRITE) < 0) {
      if (source) zip_source_free(source);
      zip_discard(zip);
      throw std::runtime_error("cannot add " + name + " to " + path.string());
    }
  }
  if (zip_close(zip) != 0) {
    zip_discard(zip);
    throw std::runtime_error("cannot write " + path.string());
  }
}

std::map<std::string, std::vector<uint8_t>> test_map_files(const TestMap& map) {
  std::map<std::string, std::vector<uint8_t>> files;
  files["maps/tiny.bsp"] = write_bsp(map.bsp);
  files["textures/test/floor.tga"] = encode_tga(4, 4, 3, uniform_rgb(4, 4, map.floor_texel), false);
  std::vector<uint8_t> jpg;
  const cv::Mat wall(8, 8, CV_8UC3, cv::Scalar(90, 110, 130));  // BGR
  cv::imencode(".jpg", wall, jpg);
  files["textures/test/wall.jpg"] = jpg;
  files["textures/test/patch.tga"] = encode_tga(2, 2, 3, uniform_rgb(2, 2, {120, 200, 120}), true);
  files["textures/test/mesh.tga"] = encode_tga(2, 2, 3, uniform_rgb(2, 2, {255, 255, 255}), true);
  std::vector<uint8_t> grate;
  for (int i = 0; i < 16; ++i) grate.insert(grate.end(), {200, 200, 200, static_cast<uint8_t>(i % 2 ? 255 : 0)});
  files["textures/test/grate.tga"] = encode_tga(4, 4, 4, grate, true);
  const std::string shaders =
      "// tiny test shaders\n"
      "textures/test/sky\n{\n\tsurfaceparm sky\n\tsurfaceparm noimpact\n\tskyParms - 512 -\n"
      "\t{\n\t\tmap $whiteimage\n\t\trgbGen const ( 0.2 0.4 0.8 )\n\t}\n}\n\n"
      "textures/test/glass\n{\n\tsurfaceparm trans\n\tcull none\n\t{\n\t\tmap textures/test/wall.jpg\n"
      "\t\tblendFunc add\n\t}\n\t{\n\t\tmap $lightmap\n\t\tblendFunc filter\n\t}\n}\n\n"
      "/* a block comment */\n"
      "textures/test/grate\n{\n\tcull none\n\t{\n\t\tmap textures/test/grate.tga\n\t\talphaFunc GE128\n"
      "\t\tdepthWrite\n\t}\n\t{\n\t\tmap $lightmap\n\t\trgbGen identity\n\t\tblendFunc GL_DST_COLOR GL_ZERO\n"
      "\t\tdepthFunc equal\n\t}\n}\n";
  files["scripts/tiny.shader"] = std::vector<uint8_t>(shaders.begin(), shaders.end());
  return files;
}

TempDir::TempDir() {
  std::random_device device;
  path_ = std::filesystem::temp_directory_path() /
          ("cgsr_q3_" + std::to_string(::getpid()) + "_" + std::to_string(device()));
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

}  // namespace cgsr::q3::testing
