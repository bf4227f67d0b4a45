#include "models/backbone_registry.h"

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

}  // namespace cgsr
