#include "models/backbone_registry.h"

#include <cctype>

// register_backbone_files(): declares and calls register_backbone_<name> of every
// models/backbones/<name>.cpp; generated when configuring (models/CMakeLists.txt).
#include "models/backbone_files.inc"

namespace cgsr {

Registry<BackboneInfo>& backbone_registry() {
  static Registry<BackboneInfo> registry = [] {
    Registry<BackboneInfo> r("backbone");
    register_builtin_backbones(r);
    return r;
  }();
  return registry;
}

void register_builtin_backbones(Registry<BackboneInfo>& registry) { register_backbone_files(registry); }

std::string block_group(int block, const std::string& suffix) {
  return "block" + std::to_string(block) + "_" + suffix;
}

std::optional<std::pair<int, std::string>> parse_block_group(const std::string& name) {
  static const std::string prefix = "block";
  if (name.rfind(prefix, 0) != 0) return std::nullopt;
  size_t pos = prefix.size();
  int block = 0;
  while (pos < name.size() && std::isdigit(static_cast<unsigned char>(name[pos])) && block < 100000)
    block = block * 10 + (name[pos++] - '0');
  if (pos == prefix.size() || pos >= name.size() || name[pos] != '_') return std::nullopt;
  return std::make_pair(block, name.substr(pos + 1));
}

}  // namespace cgsr
