#include "pipeline/stage_cache.h"

#include <cstdio>

#include "core/atomic_file.h"
#include "core/config.h"
#include "core/error.h"
#include "core/hash.h"

namespace cgsr {
namespace {
const char* kRecord = "stage.json";
}

std::string stage_hash(const YAML::Node& config, const std::vector<std::string>& upstream) {
  std::string text = config::to_yaml(config);
  for (const auto& h : upstream) text += "\n@" + h;
  const uint64_t h = fnv1a64(text, kLegacyFnv1a64Basis);  // legacy basis: existing stage caches stay current
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return hex;
}

bool stage_is_current(const std::filesystem::path& dir, const std::string& hash) {
  const auto record = dir / kRecord;
  if (!std::filesystem::exists(record)) return false;
  try {
    const auto j = nlohmann::json::parse(read_file(record));
    return j.value("hash", "") == hash && j.value("done", false);
  } catch (const nlohmann::json::exception&) {
    return false;  // unreadable record: the stage reruns
  }
}

void mark_stage_done(const std::filesystem::path& dir, const std::string& hash, const nlohmann::ordered_json& summary) {
  nlohmann::ordered_json j;
  j["hash"] = hash;
  j["done"] = true;
  j["summary"] = summary;
  write_file_atomic(dir / kRecord, j.dump(2) + "\n");
}

nlohmann::ordered_json stage_summary(const std::filesystem::path& dir) {
  const auto record = dir / kRecord;
  try {
    return nlohmann::ordered_json::parse(read_file(record)).at("summary");
  } catch (const nlohmann::json::exception& e) {
    throw Error(record.string(), std::string("unreadable stage record: ") + e.what());
  }
}

}  // namespace cgsr
