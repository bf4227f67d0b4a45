#pragma once
// Quake III game data: pk3 files are zip archives, and the game sees the union of all of them as
// one file system in which a later archive (alphabetical order, base directory first) overrides a
// file of the same name in an earlier one. Names are matched case-insensitively, as the game does.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

namespace cgsr::q3 {

// One pk3 archive, opened read-only through libzip. Errors name the archive (and the entry).
class Pk3Archive {
 public:
  explicit Pk3Archive(const std::filesystem::path& path);
  ~Pk3Archive();
  Pk3Archive(const Pk3Archive&) = delete;
  Pk3Archive& operator=(const Pk3Archive&) = delete;

  const std::filesystem::path& path() const { return path_; }
  // File entries (directories left out), in archive order.
  const std::vector<std::string>& entries() const { return names_; }
  // The bytes of entry `index` (into entries()). Entries above 512 MiB are refused.
  std::vector<uint8_t> read(size_t index) const;

 private:
  std::filesystem::path path_;
  struct Handle;
  std::unique_ptr<Handle> handle_;
  std::vector<std::string> names_;
  std::vector<uint64_t> zip_indices_;  // libzip index of each entry in names_
};

// The game's virtual file system over many archives.
class Pk3FileSystem {
 public:
  // Adds one archive; its files override same-named files of archives added before it.
  void add_archive(const std::filesystem::path& path);
  // Adds every *.pk3 of `directory` in alphabetical order (the game's order). Returns how many.
  int add_directory(const std::filesystem::path& directory);

  size_t archive_count() const { return archives_.size(); }
  size_t file_count() const { return files_.size(); }
  bool contains(const std::string& name) const;
  // The file's bytes; cgsr::Error naming the file when no archive holds it.
  std::vector<uint8_t> read(const std::string& name) const;
  std::optional<std::vector<uint8_t>> try_read(const std::string& name) const;
  // "pak1-maps.pk3:maps/oa_dm1.bsp", for messages; "" when absent.
  std::string describe(const std::string& name) const;
  // Names (as stored, lower case) that start with `prefix` and end with `suffix`, sorted.
  std::vector<std::string> list(const std::string& prefix, const std::string& suffix) const;

 private:
  struct Location {
    size_t archive = 0;
    size_t entry = 0;
  };
  const Location* find(const std::string& name) const;
  std::vector<std::unique_ptr<Pk3Archive>> archives_;
  std::unordered_map<std::string, Location> files_;  // lower-case name -> newest location
  mutable std::mutex mutex_;                          // libzip handles are not thread-safe
};

// Lower case with '\\' turned into '/': the key under which the game looks a file up.
std::string normalize_game_path(const std::string& name);

}  // namespace cgsr::q3
