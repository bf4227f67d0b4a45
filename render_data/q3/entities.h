#pragma once
// The BSP's entity string: a list of blocks `{ "key" "value" ... }`, e.g.
//   { "classname" "info_player_deathmatch" "origin" "-64 128 24" "angle" "90" }
// parse_entities turns it into key/value maps; errors name the file and the line.

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "render_data/vec_math.h"

namespace cgsr::q3 {

struct Entity {
  std::map<std::string, std::string> keys;  // a repeated key keeps its last value, as in the game
  int line = 0;                             // line of the opening brace, for messages

  std::string classname() const { return get("classname"); }
  std::string get(const std::string& key, const std::string& fallback = "") const;
  // "x y z" as a vector; nullopt when the key is absent; cgsr::Error when it is malformed.
  std::optional<Vec3> vector(const std::string& key, const std::string& context) const;
  // The facing direction in degrees around Z ("angle", or the yaw of "angles"); 0 when absent.
  float yaw_degrees(const std::string& context) const;
};

// `context` names the source in errors ("maps/oa_dm1.bsp: entities").
std::vector<Entity> parse_entities(const std::string& text, const std::string& context);

// Where a player may start: info_player_deathmatch, info_player_start (and the team spawns of CTF
// maps, team_CTF_redspawn / team_CTF_bluespawn / team_CTF_redplayer / team_CTF_blueplayer).
bool is_spawn_point(const Entity& entity);
// Pick-ups: item_*, weapon_*, ammo_*, holdable_*.
bool is_item(const Entity& entity);

}  // namespace cgsr::q3
