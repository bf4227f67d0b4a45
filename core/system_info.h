#pragma once
// What this build and machine are: library versions, threads, SIMD level, build type.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace cgsr {

nlohmann::ordered_json system_info();

// The CPU's model name (/proc/cpuinfo), or "unknown CPU".
std::string cpu_model();

// Where cgsr keeps what it decides once per machine (e.g. the memory layouts of
// models/memory_layout.h): $CGSR_CACHE_DIR, else $XDG_CACHE_HOME/cgsr, else $HOME/.cache/cgsr;
// empty when none of them is set.
std::filesystem::path user_cache_dir();

}  // namespace cgsr
