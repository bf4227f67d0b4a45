#pragma once
// Running a helper program (node for ONNX Runtime, python3 for torch.jit.load) and collecting
// its exit status and output. Output goes through temporary files, so a chatty child can never
// block on a full pipe.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace cgsr {

struct ProcessResult {
  int exit_code = -1;  // the child's exit status; 128 + signal when killed by one
  std::string out, err;
};

// Runs argv[0] (searched in PATH when it has no '/') with the given arguments and waits.
// Throws cgsr::Error when the program cannot be started.
ProcessResult run_process(const std::vector<std::string>& argv);

// The full path of an executable found in PATH (or the path itself when it contains '/' and is
// executable); nullopt when there is none.
std::optional<std::filesystem::path> find_executable(const std::string& name);

// A fresh private directory under the system temp dir, removed with its content on destruction.
class TempDir {
 public:
  explicit TempDir(const std::string& prefix);
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace cgsr
