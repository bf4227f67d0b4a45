#pragma once
// Quake III shader scripts (scripts/*.shader): a shader name maps to surface parameters and a
// list of rendering stages. The loader only needs what decides how a surface is drawn by a
// renderer without multi-pass blending:
//   - which image is the surface's colour (the first stage that maps an image, not $lightmap),
//   - whether the surface is opaque, alpha-tested, blended (transparent) or sky,
//   - surfaceparms such as nodraw, sky, trans, fog, nolightmap.
// Animation (tcMod, deformVertexes, rgbGen waves) is ignored: frames show the first state.

#include <array>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace cgsr::q3 {

class Pk3FileSystem;

struct ShaderStage {
  std::string map;                 // image path, "$lightmap", "$whiteimage", or "" (no map line)
  std::string blend_src, blend_dst;  // lower-case GL factors; empty when the stage does not blend
  std::string alpha_func;          // lower case: "gt0", "lt128", "ge128", or ""
  std::string rgb_gen;             // lower case: "identity", "vertex", "exactvertex", "const", ... or ""
  std::optional<std::array<float, 3>> constant_color;  // rgbGen const ( r g b )
  bool blends() const { return !blend_src.empty() && !(blend_src == "gl_one" && blend_dst == "gl_zero"); }
};

struct ShaderDefinition {
  std::string name;  // lower case
  std::string file;  // the script it came from
  int line = 0;
  std::set<std::string> surface_params;  // lower case: "nodraw", "sky", "trans", "fog", ...
  std::string sky_farbox;                // skyParms' first argument ("-" or a path prefix)
  bool cull_none = false;
  std::vector<ShaderStage> stages;

  bool has(const std::string& surface_param) const { return surface_params.count(surface_param) > 0; }
  // The first stage that maps a real image (not $lightmap / $whiteimage); nullptr if none.
  const ShaderStage* colour_stage() const;
};

// How a shader is drawn without blending passes.
enum class ShaderLook { Opaque, AlphaTested, Transparent, Sky, Invisible };
ShaderLook classify(const ShaderDefinition& shader);

class ShaderLibrary {
 public:
  // Parses one script. A syntax error ends that script (the shaders before it are kept) and is
  // recorded in problems(), as the game does; nothing is dropped silently.
  void add_script(const std::string& text, const std::string& file);
  // Every scripts/*.shader of the file system, in name order (a later definition of a shader
  // name replaces an earlier one).
  void add_all_scripts(const Pk3FileSystem& files);

  const ShaderDefinition* find(const std::string& name) const;  // case-insensitive
  size_t size() const { return shaders_.size(); }
  const std::vector<std::string>& problems() const { return problems_; }

 private:
  std::map<std::string, ShaderDefinition> shaders_;
  std::vector<std::string> problems_;
};

}  // namespace cgsr::q3
