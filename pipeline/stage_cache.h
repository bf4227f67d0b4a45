#pragma once
// Caching of pipeline stages (`cgsr run`): a stage directory records the hash of everything
// that produced it (its resolved config and the hashes of the stages it reads). A rerun skips a
// stage whose record matches; a changed config, a changed upstream stage or `--from` reruns it.
// The record is written last and atomically, so a killed stage is never taken for finished.

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace cgsr {

// A stable hash (hex) of a config node and upstream stage hashes.
std::string stage_hash(const YAML::Node& config, const std::vector<std::string>& upstream);

// True when `dir` holds a finished stage made with `hash`.
bool stage_is_current(const std::filesystem::path& dir, const std::string& hash);

void mark_stage_done(const std::filesystem::path& dir, const std::string& hash, const nlohmann::ordered_json& summary);
nlohmann::ordered_json stage_summary(const std::filesystem::path& dir);  // what mark_stage_done recorded

}  // namespace cgsr
