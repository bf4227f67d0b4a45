#include "render_data/q3/shader_script.h"

#include <spdlog/spdlog.h>

#include <cmath>
#include <sstream>

#include "core/error.h"
#include "render_data/q3/pk3_archive.h"
#include "render_data/q3/script_tokens.h"

namespace cgsr::q3 {
namespace {

// The game's shorthand blend modes.
void set_blend(ShaderStage& stage, const std::vector<std::string>& args) {
  if (args.size() == 1) {
    const std::string mode = ascii_lower(args[0]);
    if (mode == "add") stage.blend_src = "gl_one", stage.blend_dst = "gl_one";
    else if (mode == "filter") stage.blend_src = "gl_dst_color", stage.blend_dst = "gl_zero";
    else if (mode == "blend") stage.blend_src = "gl_src_alpha", stage.blend_dst = "gl_one_minus_src_alpha";
    else stage.blend_src = mode, stage.blend_dst = "gl_zero";
  } else if (args.size() >= 2) {
    stage.blend_src = ascii_lower(args[0]);
    stage.blend_dst = ascii_lower(args[1]);
  }
}

// Walks the tokens of one script, one directive (the tokens of a line) at a time.
class ShaderParser {
 public:
  ShaderParser(const std::vector<ScriptToken>& tokens, const std::string& file) : t_(tokens), file_(file) {}

  bool done() const { return i_ >= t_.size(); }

  ShaderDefinition next_shader() {
    const ScriptToken& name = t_[i_++];
    if (name.kind != ScriptToken::Text) fail(name.line, "expected a shader name, got '" + name.text + "'");
    ShaderDefinition shader;
    shader.name = ascii_lower(name.text);
    shader.file = file_;
    shader.line = name.line;
    expect_open(name.line);
    for (;;) {
      if (done()) fail(name.line, "shader '" + name.text + "' is not closed with '}'");
      const ScriptToken& t = t_[i_];
      if (t.kind == ScriptToken::Close) {
        ++i_;
        return shader;
      }
      if (t.kind == ScriptToken::Open) {
        ++i_;
        shader.stages.push_back(parse_stage(t.line));
        continue;
      }
      const std::vector<std::string> d = directive();
      const std::string key = ascii_lower(d[0]);
      if (key == "surfaceparm" && d.size() > 1) shader.surface_params.insert(ascii_lower(d[1]));
      else if ((key == "cull") && d.size() > 1) shader.cull_none = ascii_lower(d[1]) == "none" || ascii_lower(d[1]) == "disable" || ascii_lower(d[1]) == "twosided";
      else if (key == "skyparms" && d.size() > 1) shader.sky_farbox = d[1];
    }
  }

  [[noreturn]] void fail(int line, const std::string& what) const {
    throw Error(file_, "line " + std::to_string(line) + ": " + what);
  }

 private:
  void expect_open(int line) {
    if (done() || t_[i_].kind != ScriptToken::Open) fail(line, "expected '{' after the shader name");
    ++i_;
  }

  // The text tokens of the current line (stops at a brace).
  std::vector<std::string> directive() {
    std::vector<std::string> out;
    const int line = t_[i_].line;
    while (!done() && t_[i_].kind == ScriptToken::Text && t_[i_].line == line) out.push_back(t_[i_++].text);
    return out;
  }

  ShaderStage parse_stage(int open_line) {
    ShaderStage stage;
    for (;;) {
      if (done()) fail(open_line, "stage is not closed with '}'");
      const ScriptToken& t = t_[i_];
      if (t.kind == ScriptToken::Close) {
        ++i_;
        return stage;
      }
      if (t.kind == ScriptToken::Open) fail(t.line, "unexpected '{' inside a stage");
      const std::vector<std::string> d = directive();
      const std::string key = ascii_lower(d[0]);
      if ((key == "map" || key == "clampmap") && d.size() > 1) {
        stage.map = d[1];
      } else if (key == "animmap" && d.size() > 2) {
        stage.map = d[2];  // animMap <frequency> <frame 1> ...: the first frame
      } else if (key == "blendfunc") {
        set_blend(stage, {d.begin() + 1, d.end()});
      } else if (key == "alphafunc" && d.size() > 1) {
        stage.alpha_func = ascii_lower(d[1]);
      } else if (key == "rgbgen" && d.size() > 1) {
        stage.rgb_gen = ascii_lower(d[1]);
        if (stage.rgb_gen != "const") continue;
        // rgbGen const ( r g b ), parentheses attached to the numbers or not.
        std::string numbers;
        for (size_t k = 2; k < d.size(); ++k) numbers += d[k] + " ";
        for (char& c : numbers)
          if (c == '(' || c == ')') c = ' ';
        std::istringstream in(numbers);
        std::vector<float> values;
        for (float v; in >> v;)
          if (std::isfinite(v)) values.push_back(v);
        if (values.size() == 3) stage.constant_color = std::array<float, 3>{values[0], values[1], values[2]};
      }
    }
  }

  const std::vector<ScriptToken>& t_;
  const std::string& file_;
  size_t i_ = 0;
};

}  // namespace

const ShaderStage* ShaderDefinition::colour_stage() const {
  for (const auto& stage : stages) {
    const std::string m = ascii_lower(stage.map);
    if (!m.empty() && m != "$lightmap" && m != "$whiteimage") return &stage;
  }
  return nullptr;
}

ShaderLook classify(const ShaderDefinition& shader) {
  if (shader.has("nodraw") || shader.has("fog")) return ShaderLook::Invisible;
  if (shader.has("sky")) return ShaderLook::Sky;
  if (shader.stages.empty()) return ShaderLook::Invisible;  // the game draws nothing for it
  // Blending in the first stage mixes with what is behind the surface.
  if (shader.stages.front().blends()) return ShaderLook::Transparent;
  const ShaderStage* colour = shader.colour_stage();
  if (colour && !colour->alpha_func.empty()) return ShaderLook::AlphaTested;
  return ShaderLook::Opaque;
}

void ShaderLibrary::add_script(const std::string& text, const std::string& file) {
  std::vector<ScriptToken> tokens;
  try {
    tokens = tokenize_script(text, file);
  } catch (const Error& e) {
    problems_.push_back(e.what());
    return;
  }
  ShaderParser parser(tokens, file);
  try {
    while (!parser.done()) {
      ShaderDefinition shader = parser.next_shader();
      shaders_[shader.name] = std::move(shader);
    }
  } catch (const Error& e) {
    problems_.push_back(e.what());
  }
}

void ShaderLibrary::add_all_scripts(const Pk3FileSystem& files) {
  for (const std::string& name : files.list("scripts/", ".shader")) {
    const std::vector<uint8_t> bytes = files.read(name);
    add_script(std::string(bytes.begin(), bytes.end()), files.describe(name));
  }
  for (const auto& problem : problems_) spdlog::warn("shader script: {}", problem);
}

const ShaderDefinition* ShaderLibrary::find(const std::string& name) const {
  const auto it = shaders_.find(ascii_lower(name));
  return it == shaders_.end() ? nullptr : &it->second;
}

}  // namespace cgsr::q3
