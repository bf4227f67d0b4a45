#include "render_data/q3/entities.h"

#include <cmath>
#include <sstream>

#include "core/error.h"
#include "render_data/q3/script_tokens.h"

namespace cgsr::q3 {
namespace {

bool starts_with(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

}  // namespace

std::string Entity::get(const std::string& key, const std::string& fallback) const {
  const auto it = keys.find(key);
  return it == keys.end() ? fallback : it->second;
}

std::optional<Vec3> Entity::vector(const std::string& key, const std::string& context) const {
  const auto it = keys.find(key);
  if (it == keys.end()) return std::nullopt;
  std::istringstream in(it->second);
  Vec3 v;
  std::string rest;
  if (!(in >> v.x >> v.y >> v.z) || (in >> rest) || !std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
    throw Error(context, "entity at line " + std::to_string(line) + " (" + classname() + "): key '" + key +
                             "' = '" + it->second + "' is not three finite numbers");
  return v;
}

float Entity::yaw_degrees(const std::string& context) const {
  if (const auto angles = vector("angles", context)) return angles->y;  // pitch yaw roll
  const auto it = keys.find("angle");
  if (it == keys.end()) return 0.0f;
  std::istringstream in(it->second);
  float yaw = 0;
  if (!(in >> yaw) || !std::isfinite(yaw))
    throw Error(context, "entity at line " + std::to_string(line) + " (" + classname() + "): key 'angle' = '" +
                             it->second + "' is not a number");
  return yaw;
}

std::vector<Entity> parse_entities(const std::string& text, const std::string& context) {
  const std::vector<ScriptToken> tokens = tokenize_script(text, context);
  auto fail = [&](int line, const std::string& what) {
    throw Error(context, "line " + std::to_string(line) + ": " + what);
  };
  std::vector<Entity> out;
  size_t i = 0;
  while (i < tokens.size()) {
    if (tokens[i].kind != ScriptToken::Open) fail(tokens[i].line, "expected '{' to open an entity");
    Entity entity;
    entity.line = tokens[i++].line;
    for (;;) {
      if (i >= tokens.size()) fail(entity.line, "entity is not closed with '}'");
      const ScriptToken& key = tokens[i++];
      if (key.kind == ScriptToken::Close) break;
      if (key.kind != ScriptToken::Text) fail(key.line, "expected a key or '}'");
      if (i >= tokens.size() || tokens[i].kind != ScriptToken::Text) fail(key.line, "key '" + key.text + "' has no value");
      entity.keys[key.text] = tokens[i++].text;
    }
    out.push_back(std::move(entity));
  }
  return out;
}

bool is_spawn_point(const Entity& entity) {
  const std::string c = entity.classname();
  return c == "info_player_deathmatch" || c == "info_player_start" || c == "team_CTF_redspawn" ||
         c == "team_CTF_bluespawn" || c == "team_CTF_redplayer" || c == "team_CTF_blueplayer";
}

bool is_item(const Entity& entity) {
  const std::string c = entity.classname();
  return starts_with(c, "item_") || starts_with(c, "weapon_") || starts_with(c, "ammo_") || starts_with(c, "holdable_");
}

}  // namespace cgsr::q3
