#pragma once
// Backbones by name: what each one is (layer groups with their default widths, block range,
// colour modes) and how to build it from a spec.
//
// Adding a backbone is adding one file, models/backbones/<name>.cpp, that defines
//   void register_backbone_<name>(Registry<BackboneInfo>& registry);  // registry.add("<name>", ...)
// Nothing else is edited: configuring globs models/backbones/*.cpp and generates the list that
// register_builtin_backbones() calls, in file-name order (models/CMakeLists.txt). The registry
// is filled explicitly on first use, never by static initializers. Worked example:
// docs/extending.md.

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/registry.h"
#include "models/arch_spec.h"
#include "models/backbone.h"

namespace cgsr {

struct GroupDefault {
  std::string name;
  int width = 0;
};

struct BackboneInfo {
  std::string description;
  int default_blocks = 0;
  int min_blocks = 0;
  int max_blocks = 0;
  bool supports_y = false;  // may run on BT.601 luma (colors: y)
  bool has_image_skip = false;  // adds the interpolated LR image to its output (image_skip)
  // Has features at the output resolution before its last convolution: where the RIT's HR branch
  // (rit.source hr_fuse) and the geometry head read. A backbone whose last layer upsamples has none.
  bool has_hr_features = true;
  // The blocks no subnet may skip, given the block count (e.g. one whose inner value a later
  // layer reads); none when unset.
  std::function<std::vector<int>(int blocks)> fixed_blocks;
  // Per-block groups are named "block<i>_<suffix>"; the suffixes, for error messages.
  std::vector<std::string> block_group_suffixes;
  // Every layer group of a network with this scale and block count, in canonical order.
  std::function<std::vector<GroupDefault>(int scale, int blocks)> groups;
  // Builds the backbone of a resolved, validated spec.
  std::function<std::shared_ptr<BackboneImpl>(const ArchSpec& spec)> build;
};

// The process-wide table, the built-in backbones already in it. A program that embeds cgsr may
// add its own with registry.add (before it builds networks; names are unique).
Registry<BackboneInfo>& backbone_registry();
// Calls register_backbone_<name> of every file in models/backbones/.
void register_builtin_backbones(Registry<BackboneInfo>& registry);

// "block3_a"
std::string block_group(int block, const std::string& suffix);
// The inverse: (block, suffix) of a name block_group made, nothing for other group names.
std::optional<std::pair<int, std::string>> parse_block_group(const std::string& name);

}  // namespace cgsr
