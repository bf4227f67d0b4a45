#include "render_data/q3/game_data.h"

#include <algorithm>

#include "core/error.h"

namespace cgsr::q3 {

std::unique_ptr<Pk3FileSystem> mount_game_data(const GameDataOptions& options) {
  auto files = std::make_unique<Pk3FileSystem>();
  if (!options.root.empty()) {
    namespace fs = std::filesystem;
    const fs::path root(options.root);
    std::error_code ec;
    const std::string missing = std::string("OpenArena game data not found: the Debian packages ") +
                                kOpenArenaPackages + " are not installed. Install them with: " + kOpenArenaInstall;
    if (!fs::is_directory(root / "baseoa", ec)) throw Error(options.root, missing);
    std::vector<fs::path> others;
    for (const auto& entry : fs::directory_iterator(root, ec))
      if (entry.is_directory() && entry.path().filename() != "baseoa") others.push_back(entry.path());
    std::sort(others.begin(), others.end());
    int archives = files->add_directory(root / "baseoa");
    for (const auto& dir : others) archives += files->add_directory(dir);
    if (archives == 0) throw Error(options.root, missing);
  }
  for (const auto& pk3 : options.extra_pk3) files->add_archive(pk3);
  if (files->archive_count() == 0) throw Error("game data", "no pk3 archive to read: set a data root or extra pk3 files");
  return files;
}

std::string map_path(const std::string& map) {
  if (map.find('/') != std::string::npos || (map.size() > 4 && map.compare(map.size() - 4, 4, ".bsp") == 0))
    return map;
  return "maps/" + map + ".bsp";
}

}  // namespace cgsr::q3
