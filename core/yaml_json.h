#pragma once
// YAML -> JSON, for recording resolved configs inside JSON artifacts (results, model files).
// Scalars become integers, numbers or booleans when they read as such, strings otherwise.

#include <yaml-cpp/yaml.h>

#include <nlohmann/json.hpp>

namespace cgsr {

nlohmann::ordered_json yaml_to_json(const YAML::Node& node);

}  // namespace cgsr
