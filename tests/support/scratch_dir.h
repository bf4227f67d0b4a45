#pragma once
// Scratch directories for tests: fresh, unique per process and name, and removed when the test
// process exits, so that running the suite again and again leaves the temp dir as it found it.
// CGSR_KEEP_TEST_DIRS=1 keeps them, to look at what a failing test wrote.

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

namespace cgsr::test {

inline std::filesystem::path scratch_dir(const std::string& name) {
  static std::vector<std::filesystem::path> made;
  // Registered after `made` is built, so it runs before `made` is destroyed.
  static const bool removes_at_exit = [] {
    return std::atexit([] {
      if (std::getenv("CGSR_KEEP_TEST_DIRS")) return;
      std::error_code ignored;  // a directory that cannot be removed is not the test's failure
      for (const auto& dir : made) std::filesystem::remove_all(dir, ignored);
    }) == 0;
  }();
  (void)removes_at_exit;
  const auto dir = std::filesystem::temp_directory_path() / ("cgsr-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  made.push_back(dir);
  return dir;
}

}  // namespace cgsr::test
