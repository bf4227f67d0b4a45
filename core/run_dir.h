#pragma once
// A command's run directory (--out DIR): the resolved config.yaml, log.txt and results.json,
// plus whatever artifacts the command writes. Every file is written atomically.

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace cgsr {

class RunDir {
 public:
  // Creates the directory; with `own_log`, also logs into its log.txt until destroyed (a
  // pipeline stage's directory shares the pipeline's log instead).
  explicit RunDir(std::filesystem::path dir, bool own_log = true);
  ~RunDir();
  RunDir(const RunDir&) = delete;
  RunDir& operator=(const RunDir&) = delete;

  const std::filesystem::path& path() const { return dir_; }
  std::filesystem::path file(const std::string& name) const { return dir_ / name; }

  void write_config(const YAML::Node& resolved) const;
  void write_results(const nlohmann::ordered_json& results) const;

 private:
  std::filesystem::path dir_;
  bool own_log_;
};

// "runs/<command>-YYYYmmdd-HHMMSS": the default --out of a command that produces artifacts.
std::filesystem::path default_run_dir(const std::string& command);

}  // namespace cgsr
