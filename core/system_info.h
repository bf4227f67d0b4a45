#pragma once
// What this build and machine are: library versions, threads, SIMD level, build type.

#include <nlohmann/json.hpp>

namespace cgsr {

nlohmann::ordered_json system_info();

}  // namespace cgsr
