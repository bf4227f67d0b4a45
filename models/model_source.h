#pragma once
// Resolving a --model argument: a backbone name (its default spec), a spec YAML file, or a
// model file. Used by `cgsr info`, `cgsr bench` and any command that takes NAME_OR_FILE.

#include <optional>
#include <string>

#include "models/model_file.h"

namespace cgsr {

struct ModelSource {
  enum class Kind { Name, SpecFile, ModelFile };
  Kind kind = Kind::Name;
  std::string origin;  // the argument as given
  ArchSpec spec;
  std::optional<Provenance> provenance;  // model files only
  SRNetwork network{nullptr};            // trained weights for model files, fresh initialization otherwise
};

// `scale` 0 means: the file's scale, or 2 for a name. A scale that contradicts a file is an error.
ModelSource resolve_model(const std::string& name_or_file, int scale);

}  // namespace cgsr
