#include "models/backbone_registry.h"

#include <cctype>

#include "models/backbones/edsr.h"
#include "models/backbones/pan.h"
#include "models/backbones/srcnn.h"

namespace cgsr {

const Registry<BackboneInfo>& backbone_registry() {
  static const Registry<BackboneInfo> registry = [] {
    Registry<BackboneInfo> r("backbone");
    register_builtin_backbones(r);
    return r;
  }();
  return registry;
}

void register_builtin_backbones(Registry<BackboneInfo>& registry) {
  registry.add("srcnn", srcnn_info(), srcnn_info().description);
  registry.add("edsr", edsr_info(), edsr_info().description);
  registry.add("pan", pan_info(), pan_info().description);
}

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
