#include "render_data/q3/q3_level.h"

#include <spdlog/spdlog.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <tuple>

#include "core/color.h"
#include "core/error.h"
#include "render_data/q3/bezier_patch.h"
#include "render_data/q3/pk3_archive.h"
#include "render_data/q3/script_tokens.h"
#include "render_data/q3/shader_script.h"
#include "render_data/q3/texture_resolver.h"

namespace cgsr::q3 {
namespace {

// sRGB byte -> linear value, from core's transfer function.
const std::array<float, 256>& srgb_byte_to_linear() {
  static const std::array<float, 256> table = [] {
    const torch::Tensor linear = srgb_to_linear(torch::arange(256, torch::kFloat32) / 255.0f).contiguous();
    std::array<float, 256> t{};
    std::copy(linear.data_ptr<float>(), linear.data_ptr<float>() + 256, t.begin());
    return t;
  }();
  return table;
}
float linear_of(float display) { return srgb_to_linear(torch::full({1}, display)).item<float>(); }

// Editor and compiler textures the game never draws.
bool is_tool_texture(const std::string& name) {
  static const std::set<std::string> tools = {
      "caulk",     "clip",       "full_clip", "weapclip",      "playerclip",   "trigger",   "hint",
      "skip",      "nodraw",     "nodrawnonsolid", "origin",   "areaportal",   "clusterportal",
      "donotenter", "botclip",   "nodrop",    "lightgrid",     "antiportal",   "slick"};
  const std::string n = ascii_lower(name);
  const std::string prefix = "textures/common/";
  return n.rfind(prefix, 0) == 0 && tools.count(n.substr(prefix.size())) > 0;
}

enum class Lighting { Lightmap, Vertex, Fullbright };

// How one BSP texture (shader reference) is drawn, before the face's lightmap is known.
struct SurfaceLook {
  ShaderLook look = ShaderLook::Opaque;
  std::string image;                    // "" for a flat colour
  std::optional<std::array<float, 3>> flat_color;  // display-space colour of a $whiteimage stage
  const ShaderDefinition* script = nullptr;
  std::string rgb_gen;                  // of the colour stage
  bool two_sided = false;
};

class LevelBuilder {
 public:
  LevelBuilder(const BspFile& bsp, const ShaderLibrary& shaders, const Pk3FileSystem& files,
               const Q3LevelOptions& options)
      : bsp_(bsp), shaders_(shaders), files_(files), options_(options), resolver_(files),
        lightmap_textures_(bsp.lightmaps.size(), -1), sky_faces_(bsp.textures.size(), 0) {
    CGSR_CHECK(options.patch_level >= 1, "patch level must be >= 1");
    for (size_t t = 0; t < bsp.textures.size(); ++t) looks_.push_back(look_of(bsp.textures[t]));
    level_.scene.name = bsp.name;
    level_.scene.ambient = {0, 0, 0};  // no dynamic lighting: everything is baked or fullbright
    level_.stats.non_finite_coordinates = bsp.non_finite_coordinates;
  }

  Q3Level build() {
    int next_object = static_cast<int>(bsp_.models.size());
    for (size_t m = 0; m < bsp_.models.size(); ++m) {
      const BspModel& model = bsp_.models[m];
      for (int i = 0; i < model.face_count; ++i) {
        const BspFace& face = bsp_.faces[model.first_face + i];
        const int object = face.type == FaceType::Polygon ? static_cast<int>(m) : next_object;
        if (add_face(face, object) && face.type != FaceType::Polygon) ++next_object;
      }
    }
    set_sky_colors();
    Q3LevelStats& s = level_.stats;
    s.textures_loaded = static_cast<int>(std::count_if(texture_index_.begin(), texture_index_.end(),
                                                       [](const auto& kv) { return kv.second >= 0; }));
    return std::move(level_);
  }

 private:
  SurfaceLook look_of(const BspTexture& texture) {
    SurfaceLook look;
    look.script = shaders_.find(texture.name);
    Q3LevelStats& s = level_.stats;
    if (!look.script) {
      ++s.shaders_without_script;
      look.image = texture.name;
      if ((texture.surface_flags & surface_flags::kSky) || ascii_lower(texture.name).find("sky") != std::string::npos)
        look.look = ShaderLook::Sky;
      return look;
    }
    ++s.shaders_with_script;
    const ShaderDefinition& sh = *look.script;
    look.look = classify(sh);
    if (texture.surface_flags & surface_flags::kSky) look.look = ShaderLook::Sky;
    look.two_sided = sh.cull_none;
    if (const ShaderStage* colour = sh.colour_stage()) {
      look.image = colour->map;
      look.rgb_gen = colour->rgb_gen;
    } else {
      for (const auto& stage : sh.stages)
        if (ascii_lower(stage.map) == "$whiteimage") {
          look.flat_color = stage.constant_color.value_or(std::array<float, 3>{1, 1, 1});
          look.rgb_gen = stage.rgb_gen;
          break;
        }
      if (!look.flat_color) look.flat_color = std::array<float, 3>{1, 1, 1};  // only a $lightmap stage
    }
    return look;
  }

  // Drawn (true) or skipped and counted (false).
  bool add_face(const BspFace& face, int object) {
    Q3LevelStats& s = level_.stats;
    ++s.faces;
    if (face.type == FaceType::Billboard) {
      ++s.skipped_billboards;
      return false;
    }
    const BspTexture& texture = bsp_.textures[face.texture];
    const SurfaceLook& look = looks_[face.texture];
    if ((texture.surface_flags & surface_flags::kNoDraw) || (texture.contents & contents::kFog) ||
        is_tool_texture(texture.name) || look.look == ShaderLook::Invisible) {
      ++s.skipped_invisible;
      return false;
    }
    if (look.look == ShaderLook::Transparent) {
      ++s.skipped_transparent;
      return false;
    }
    int material = 0;
    Lighting lighting = Lighting::Fullbright;
    if (look.look == ShaderLook::Sky) {
      material = sky_material();
      ++sky_faces_[face.texture];
      ++s.sky_faces;
    } else {
      lighting = lighting_of(face, look);
      material = material_for(face.texture, lighting == Lighting::Lightmap ? face.lightmap : -1, lighting);
      if (look.look == ShaderLook::AlphaTested) ++s.alpha_tested_faces;
      (lighting == Lighting::Lightmap ? s.lightmapped_faces
       : lighting == Lighting::Vertex ? s.vertex_lit_faces
                                      : s.fullbright_faces)++;
    }
    Mesh& mesh = mesh_for(material, object, texture.name);
    const bool with_colors = lighting == Lighting::Vertex;
    const uint32_t base = static_cast<uint32_t>(mesh.positions.size());
    size_t triangles = 0;
    if (face.type == FaceType::Patch) {
      const std::vector<BspVertex> control(bsp_.vertices.begin() + face.first_vertex,
                                           bsp_.vertices.begin() + face.first_vertex + face.vertex_count);
      const TessellatedPatch patch =
          tessellate_patch(control, face.patch_size[0], face.patch_size[1], options_.patch_level);
      for (const PatchVertex& v : patch.vertices)
        push_vertex(mesh, v.position, v.normal, v.uv, v.lightmap_uv, v.color.data(), with_colors, face.normal);
      push_triangles(mesh, base, patch.indices.data(), patch.indices.size());
      triangles = patch.indices.size() / 3;
      s.patch_triangles += static_cast<int>(triangles);
      ++s.patches;
    } else {
      for (int i = 0; i < face.vertex_count; ++i) {
        const BspVertex& v = bsp_.vertices[face.first_vertex + i];
        const float color[4] = {v.color[0] / 255.0f, v.color[1] / 255.0f, v.color[2] / 255.0f, v.color[3] / 255.0f};
        push_vertex(mesh, v.position, v.normal, v.uv, v.lightmap_uv, color, with_colors, face.normal);
      }
      std::vector<uint32_t> indices(face.mesh_vert_count);
      for (int k = 0; k < face.mesh_vert_count; ++k)
        indices[k] = static_cast<uint32_t>(bsp_.mesh_verts[face.first_mesh_vert + k]);
      push_triangles(mesh, base, indices.data(), indices.size());
      triangles = indices.size() / 3;
      (face.type == FaceType::Polygon ? s.polygons : s.meshes)++;
    }
    s.triangles += static_cast<int>(triangles);
    return true;
  }

  Lighting lighting_of(const BspFace& face, const SurfaceLook& look) const {
    if (face.lightmap >= 0) return Lighting::Lightmap;
    if (!look.script) return Lighting::Vertex;  // the game's implicit shader: rgbGen exactVertex
    if (look.rgb_gen == "vertex" || look.rgb_gen == "exactvertex" || look.rgb_gen == "lightingdiffuse")
      return Lighting::Vertex;
    // A lightmapped shader on a face q3map lit by vertex: the baked vertex colours are its light.
    for (const auto& stage : look.script->stages)
      if (ascii_lower(stage.map) == "$lightmap") return Lighting::Vertex;
    return Lighting::Fullbright;
  }

  // Whether the colour stage keeps the game's overbright display ramp (x 2^overbright_bits):
  // rgbGen identity / exactVertex / const and the implicit shaders do; identityLighting and vertex
  // (x identityLight) cancel it.
  bool keeps_overbright(const SurfaceLook& look, Lighting lighting) const {
    if (lighting == Lighting::Lightmap || !look.script) return true;
    const std::string& g = look.rgb_gen;
    if (g == "identity" || g == "exactvertex" || g == "const") return true;
    return lighting == Lighting::Vertex && g.empty();  // a lightmap shader lit by vertex
  }

  int material_for(int bsp_texture, int lightmap, Lighting lighting) {
    const auto key = std::make_tuple(bsp_texture, lightmap, static_cast<int>(lighting));
    if (auto it = materials_.find(key); it != materials_.end()) return it->second;
    const SurfaceLook& look = looks_[bsp_texture];
    Material mat;
    mat.name = bsp_.textures[bsp_texture].name;
    mat.two_sided = look.two_sided;
    const bool alpha = look.look == ShaderLook::AlphaTested;
    if (!look.image.empty()) mat.albedo_texture = texture_for(look.image, alpha);
    if (alpha && mat.albedo_texture >= 0) mat.alpha_cutoff = 0.5f;
    Vec3 tint{1, 1, 1};
    if (look.flat_color) tint = {linear_of((*look.flat_color)[0]), linear_of((*look.flat_color)[1]), linear_of((*look.flat_color)[2])};
    else if (mat.albedo_texture < 0) tint = Vec3{1, 1, 1} * linear_of(0.5f);  // missing image: grey
    const float linear_factor = keeps_overbright(look, lighting) ? overbright_factor(options_.overbright_bits) : 1.0f;
    if (lighting == Lighting::Lightmap) {
      mat.lightmap_texture = lightmap_texture(lightmap);
      mat.lightmap_scale = linear_factor;
      mat.name += "#lm" + std::to_string(lightmap);
    } else {
      mat.unlit = true;
      tint = tint * linear_factor;
      mat.name += lighting == Lighting::Vertex ? "#vertex" : "#fullbright";
    }
    mat.tint = tint;
    level_.scene.materials.push_back(mat);
    return materials_[key] = static_cast<int>(level_.scene.materials.size()) - 1;
  }

  int sky_material() {
    if (sky_material_ < 0) {
      Material mat;
      mat.name = "sky";
      mat.sky = true;
      level_.scene.materials.push_back(mat);
      sky_material_ = static_cast<int>(level_.scene.materials.size()) - 1;
    }
    return sky_material_;
  }

  // Scene texture of an image, loaded once; -1 when missing or undecodable (counted).
  int texture_for(const std::string& image, bool keep_alpha) {
    const std::string key = ascii_lower(image) + (keep_alpha ? "#rgba" : "");
    if (auto it = texture_index_.find(key); it != texture_index_.end()) return it->second;
    int index = -1;
    if (const auto path = resolver_.find(image)) {
      try {
        Texture texture = decode_image(files_.read(*path), *path, keep_alpha);
        level_.scene.textures.push_back(std::move(texture));
        index = static_cast<int>(level_.scene.textures.size()) - 1;
      } catch (const Error& e) {
        spdlog::warn("{}: {}", bsp_.name, e.what());
        level_.stats.undecodable_images.push_back(image);
      }
    } else {
      level_.stats.missing_images.push_back(image);
    }
    return texture_index_[key] = index;
  }

  int lightmap_texture(int lightmap) {
    int& index = lightmap_textures_[lightmap];
    if (index >= 0) return index;
    Texture t;
    t.name = "lightmap " + std::to_string(lightmap);
    t.width = t.height = kLightmapSize;
    t.channels = 3;
    t.srgb = true;  // the game multiplies lightmap bytes in display space
    const std::vector<uint8_t>& rgb = bsp_.lightmaps[lightmap].rgb;
    t.data.resize(rgb.size());
    const int shift = std::max(0, options_.map_overbright_bits - options_.overbright_bits);
    for (size_t p = 0; p < rgb.size(); p += 3) {
      const auto c = shift_lighting(&rgb[p], shift);
      std::copy(c.begin(), c.end(), t.data.begin() + p);
    }
    level_.scene.textures.push_back(std::move(t));
    return index = static_cast<int>(level_.scene.textures.size()) - 1;
  }

  Mesh& mesh_for(int material, int object, const std::string& name) {
    const auto key = std::make_pair(material, object);
    auto it = meshes_.find(key);
    if (it == meshes_.end()) {
      Mesh mesh;
      mesh.name = name + " #" + std::to_string(object);
      mesh.material = material;
      mesh.object_id = object;
      level_.scene.meshes.push_back(std::move(mesh));
      it = meshes_.emplace(key, level_.scene.meshes.size() - 1).first;
    }
    return level_.scene.meshes[it->second];
  }

  void push_vertex(Mesh& mesh, Vec3 position, Vec3 normal, Vec2 uv, Vec2 lightmap_uv, const float* color,
                   bool with_colors, Vec3 face_normal) {
    mesh.positions.push_back(position);
    Vec3 n = normalize(normal);
    if (length(n) == 0) n = normalize(face_normal);
    if (length(n) == 0) n = {0, 0, 1};
    mesh.normals.push_back(n);
    mesh.uvs.push_back(uv);
    if (level_.scene.materials[mesh.material].lightmap_texture >= 0) mesh.lightmap_uvs.push_back(lightmap_uv);
    if (with_colors) {
      const int shift = std::max(0, options_.map_overbright_bits - options_.overbright_bits);
      const uint8_t bytes[3] = {static_cast<uint8_t>(std::lround(color[0] * 255)),
                                static_cast<uint8_t>(std::lround(color[1] * 255)),
                                static_cast<uint8_t>(std::lround(color[2] * 255))};
      const auto c = shift_lighting(bytes, shift);
      const auto& lut = srgb_byte_to_linear();
      mesh.colors.push_back({lut[c[0]], lut[c[1]], lut[c[2]]});
    }
  }

  // BSP triangles are clockwise seen from the front; the scene's are counter-clockwise.
  static void push_triangles(Mesh& mesh, uint32_t base, const uint32_t* indices, size_t count) {
    for (size_t k = 0; k + 2 < count; k += 3) {
      mesh.indices.push_back(base + indices[k]);
      mesh.indices.push_back(base + indices[k + 2]);
      mesh.indices.push_back(base + indices[k + 1]);
    }
  }

  // Average linear colour of an image, or nullopt when it does not exist (a sky's farbox is
  // optional in the game) or cannot be decoded (counted).
  std::optional<Vec3> mean_color(const std::string& image) {
    if (!resolver_.find(image)) return std::nullopt;
    const int t = texture_for(image, false);
    if (t < 0) return std::nullopt;
    const Texture& tex = level_.scene.textures[t];
    const auto& lut = srgb_byte_to_linear();
    double sum[3] = {0, 0, 0};
    const size_t pixels = static_cast<size_t>(tex.width) * tex.height;
    for (size_t p = 0; p < pixels; ++p)
      for (int c = 0; c < 3; ++c) sum[c] += lut[tex.data[p * tex.channels + c]];
    return Vec3{static_cast<float>(sum[0] / pixels), static_cast<float>(sum[1] / pixels),
                static_cast<float>(sum[2] / pixels)};
  }

  // The scene's sky gradient from the most used sky shader: a farbox's top image is the zenith
  // and its side images the horizon; otherwise the first stage (image or constant colour) is the
  // zenith and the horizon is that colour lightened towards white (haze).
  void set_sky_colors() {
    const auto most = std::max_element(sky_faces_.begin(), sky_faces_.end());
    if (most == sky_faces_.end() || *most == 0) return;
    const SurfaceLook& look = looks_[most - sky_faces_.begin()];
    std::optional<Vec3> zenith, horizon;
    if (look.script && !look.script->sky_farbox.empty() && look.script->sky_farbox != "-") {
      const std::string& box = look.script->sky_farbox;
      zenith = mean_color(box + "_up");
      Vec3 sum{};
      int n = 0;
      for (const char* side : {"_ft", "_bk", "_lf", "_rt"})
        if (const auto c = mean_color(box + side)) {
          sum += *c;
          ++n;
        }
      if (n > 0) horizon = sum / static_cast<float>(n);
    }
    if (!zenith && look.script && !look.script->stages.empty()) {
      const ShaderStage& first = look.script->stages.front();
      if (first.constant_color) {
        const auto& c = *first.constant_color;
        zenith = Vec3{linear_of(c[0]), linear_of(c[1]), linear_of(c[2])};
      } else if (!first.map.empty() && first.map[0] != '$') {
        zenith = mean_color(first.map);
      }
    }
    if (!zenith && !look.image.empty()) zenith = mean_color(look.image);
    if (!zenith) return;  // keep the scene's default sky
    level_.scene.sky.zenith = *zenith;
    level_.scene.sky.horizon = horizon ? *horizon : lerp(*zenith, Vec3{1, 1, 1}, 0.3f);
  }

  const BspFile& bsp_;
  const ShaderLibrary& shaders_;
  const Pk3FileSystem& files_;
  const Q3LevelOptions& options_;
  TextureResolver resolver_;
  Q3Level level_;
  std::vector<SurfaceLook> looks_;  // per BSP texture
  std::map<std::string, int> texture_index_;
  std::map<std::tuple<int, int, int>, int> materials_;
  std::map<std::pair<int, int>, size_t> meshes_;
  std::vector<int> lightmap_textures_;
  std::vector<int> sky_faces_;  // per BSP texture
  int sky_material_ = -1;
};

}  // namespace

std::array<uint8_t, 3> shift_lighting(const uint8_t* rgb, int shift) {
  int c[3] = {rgb[0] << shift, rgb[1] << shift, rgb[2] << shift};
  const int top = std::max({c[0], c[1], c[2]});
  if (top > 255)
    for (int& v : c) v = v * 255 / top;
  return {static_cast<uint8_t>(c[0]), static_cast<uint8_t>(c[1]), static_cast<uint8_t>(c[2])};
}

float overbright_factor(int overbright_bits) { return std::pow(static_cast<float>(1 << overbright_bits), 2.2f); }

Q3Level build_level(const BspFile& bsp, const ShaderLibrary& shaders, const Pk3FileSystem& files,
                    const Q3LevelOptions& options) {
  return LevelBuilder(bsp, shaders, files, options).build();
}

}  // namespace cgsr::q3
