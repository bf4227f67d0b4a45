#pragma once
// Shared by the fuzz targets. The parsers under test read files, so each input is first written
// to a scratch file; the scratch directory is one per process and is removed at exit.

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace cgsr::fuzz {

inline const std::filesystem::path& scratch_dir() {
  // Never destroyed: the exit handler that removes the folder runs after static destructors.
  static const std::filesystem::path* dir = [] {
    const auto* d = new std::filesystem::path(std::filesystem::temp_directory_path() /
                                              ("cgsr-fuzz-" + std::to_string(::getpid())));
    std::filesystem::create_directories(*d);
    std::atexit([] {
      std::error_code ignored;
      std::filesystem::remove_all(scratch_dir(), ignored);
    });
    return d;
  }();
  return *dir;
}

// Writes `size` bytes to `relative` under the scratch directory (folders created) and returns the path.
inline std::filesystem::path write_input(const std::filesystem::path& relative, const uint8_t* data, size_t size) {
  const auto path = scratch_dir() / relative;
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(reinterpret_cast<const char*>(data), size);
  return path;
}

}  // namespace cgsr::fuzz
