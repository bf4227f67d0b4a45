#include "models/model_source.h"

#include <filesystem>

#include "core/error.h"
#include "models/backbone_registry.h"

namespace cgsr {
namespace {
bool has_yaml_extension(const std::filesystem::path& p) {
  const auto ext = p.extension().string();
  return ext == ".yaml" || ext == ".yml";
}
}  // namespace

ModelSource resolve_model(const std::string& name_or_file, int scale) {
  namespace fs = std::filesystem;
  if (name_or_file.empty()) throw Error("--model", "give a backbone name, a spec YAML file or a model file");
  ModelSource source;
  source.origin = name_or_file;
  const fs::path path(name_or_file);
  const bool looks_like_path = name_or_file.find('/') != std::string::npos || path.has_extension();
  // A registered name wins over a stray file of that name in the working directory.
  if (!looks_like_path && (backbone_registry().contains(name_or_file) || !fs::exists(path))) {
    source.kind = ModelSource::Kind::Name;
    source.spec = default_spec(name_or_file, scale == 0 ? 2 : scale);  // unknown names list the valid ones
  } else {
    if (!fs::exists(path)) throw Error(name_or_file, "no such file");
    if (fs::is_directory(path)) throw Error(name_or_file, "is a directory, not a model or spec file");
    if (is_model_file(path)) {
      source.kind = ModelSource::Kind::ModelFile;
      Model model = load_model(path);
      source.network = model.network;
      source.provenance = model.provenance;
      source.spec = model.network->spec();
    } else if (has_yaml_extension(path)) {
      source.kind = ModelSource::Kind::SpecFile;
      source.spec = load_spec_file(path);
    } else {
      throw Error(name_or_file, "neither a cgsr model file nor a spec file (.yaml)");
    }
    if (scale != 0 && scale != source.spec.scale)
      throw Error(name_or_file, "describes a x" + std::to_string(source.spec.scale) + " model, but scale " +
                                    std::to_string(scale) + " was asked for");
  }
  if (source.network.is_empty()) source.network = SRNetwork(source.spec);
  return source;
}

}  // namespace cgsr
