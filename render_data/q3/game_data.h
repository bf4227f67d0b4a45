#pragma once
// Where the OpenArena game data lives and how it is mounted. Debian installs it under
// /usr/share/games/openarena: baseoa/ (the game) and missionpack/, from the packages
// openarena-088-data (0.8.8 patch archives: pak0.pk3, pak6-patch088.pk3, 38 maps) and
// openarena-data (its dependencies bring the 0.8.1 maps, textures, models and the 0.8.5 patch).

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "render_data/q3/pk3_archive.h"

namespace cgsr::q3 {

constexpr const char* kOpenArenaPackages = "openarena-088-data openarena-data";
constexpr const char* kOpenArenaInstall = "sudo apt-get install openarena-088-data openarena-data";
constexpr const char* kOpenArenaRoot = "/usr/share/games/openarena";

struct GameDataOptions {
  std::string root = kOpenArenaRoot;  // "" mounts only `extra_pk3`
  std::vector<std::string> extra_pk3;  // mounted last, so they override the game's files
};

// Mounts root/baseoa first, then root's other game directories in alphabetical order, then the
// extra archives. A missing root (or one without pk3 files) is an error that names the Debian
// packages and the command that installs them.
std::unique_ptr<Pk3FileSystem> mount_game_data(const GameDataOptions& options);

// "maps/<name>.bsp" for a bare map name; a name with a '/' or ".bsp" is taken as a path.
std::string map_path(const std::string& map);

}  // namespace cgsr::q3
