#pragma once
// Runs the real cgsr executable from a test and captures its exit code, stdout and stderr.

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "tests/support/scratch_dir.h"

namespace cgsr::test {

struct CliResult {
  int exit_code = -1;
  std::string out, err;
  std::string all() const { return out + err; }  // for messages that may be on either stream
};

inline std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

inline nlohmann::json read_json(const std::filesystem::path& path) { return nlohmann::json::parse(slurp(path)); }

// `args` is appended to the binary path as shell words (quote them yourself where needed).
inline CliResult run_cgsr(const std::string& args) {
  static int counter = 0;
  const auto dir = std::filesystem::temp_directory_path();
  const std::string tag = std::to_string(::getpid()) + "-" + std::to_string(counter++);
  const auto out = dir / ("cgsr-out-" + tag), err = dir / ("cgsr-err-" + tag);
  const std::string command = std::string(CGSR_BINARY) + " " + args + " >" + out.string() + " 2>" + err.string() +
                              " </dev/null";
  const int status = std::system(command.c_str());
  CliResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  std::filesystem::remove(out);
  std::filesystem::remove(err);
  return r;
}

}  // namespace cgsr::test
