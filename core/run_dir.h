#pragma once
// A command's run directory (--out DIR): the resolved config.yaml, log.txt and results.json,
// plus whatever artifacts the command writes. Every file is written atomically.

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

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
  // Writes results.json, then runs the steps given to after_results.
  void write_results(const nlohmann::ordered_json& results);
  // `step` runs right after results.json is written: for what must not look finished before
  // the results do (a rendered data set's manifest marked complete).
  void after_results(std::function<void()> step);

 private:
  std::filesystem::path dir_;
  bool own_log_;
  std::vector<std::function<void()>> after_results_;
};

// "runs/<command>-YYYYmmdd-HHMMSS": the default --out of a command that produces artifacts.
std::filesystem::path default_run_dir(const std::string& command);

}  // namespace cgsr
