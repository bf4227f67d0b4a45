#include "core/yaml_json.h"

namespace cgsr {
namespace {
// JSON keys are strings. A key that is a list, a map or null is valid YAML (`? [a, b]: 1`); no
// schema accepts one, but raw blocks reach here before their schema rejects them with a file
// position, so such a key is written as its YAML flow text rather than failing here.
std::string key_text(const YAML::Node& key) {
  if (key.IsScalar()) return key.Scalar();
  YAML::Emitter out;
  out << YAML::Flow << key;
  return out.c_str();
}
}  // namespace

nlohmann::ordered_json yaml_to_json(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Sequence: {
      auto j = nlohmann::ordered_json::array();
      for (const auto& item : node) j.push_back(yaml_to_json(item));
      return j;
    }
    case YAML::NodeType::Map: {
      auto j = nlohmann::ordered_json::object();
      for (const auto& kv : node) j[key_text(kv.first)] = yaml_to_json(kv.second);
      return j;
    }
    case YAML::NodeType::Scalar: {
      if (node.Tag() == "!") return node.Scalar();  // quoted in the source: a string
      int64_t i;
      double d;
      bool b;
      if (YAML::convert<int64_t>::decode(node, i)) return i;
      if (YAML::convert<double>::decode(node, d)) return d;
      if (YAML::convert<bool>::decode(node, b)) return b;
      return node.Scalar();
    }
    default:
      return nullptr;
  }
}

}  // namespace cgsr
