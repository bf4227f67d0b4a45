#pragma once
// Model files: one self-describing file per trained network (extension .cgsr by convention).
//
//   offset  size  content
//   0       8     magic "CGSRMODL"
//   8       4     format version (little-endian uint32, currently 1)
//   12      8     metadata length M (little-endian uint64)
//   20      8     weights length W (little-endian uint64)
//   28      M     metadata: UTF-8 JSON {format, version, spec (YAML text), channels,
//                 provenance {stage, parent, config, metrics, extra}, tensors [{name, shape}]}
//   28+M    W     weights: torch::save of the tensors, in the metadata's order
//   28+M+W  8     FNV-1a 64 checksum of every byte before it (little-endian)
//
// Files are written atomically. Reading checks magic, version, lengths (truncation), the
// checksum (corruption), the spec (the same validation as a spec file) and that the weights are
// exactly the spec's parameters with the spec's shapes; every failure is a cgsr::Error naming
// the file.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "models/arch_spec.h"
#include "models/sr_network.h"

namespace cgsr {

// Where a model came from.
struct Provenance {
  std::string stage;   // e.g. "backbone", "cg-enhanced", "search", "pruned"
  std::string parent;  // the model file it was derived from, "" for none
  nlohmann::ordered_json config = nlohmann::ordered_json::object();   // resolved config of the producing command
  nlohmann::ordered_json metrics = nlohmann::ordered_json::object();  // e.g. {"psnr": 36.1, "ssim": 0.94}
  nlohmann::ordered_json extra = nlohmann::ordered_json::object();    // anything else a stage records
};

nlohmann::ordered_json to_json(const Provenance& p);
Provenance provenance_from_json(const nlohmann::ordered_json& j, const std::string& context);

// Tensors named with this prefix are not network parameters but data of a later stage (pruning
// stores its dynamic pruning components there); load_model() ignores them, so such a file still
// loads, exports and runs as a plain network.
inline constexpr const char* kExtraTensorPrefix = "extra.";

// The raw content of a model file, before a network is built from it.
struct ModelFileContents {
  ArchSpec spec;
  Provenance provenance;
  std::vector<std::pair<std::string, torch::Tensor>> tensors;  // parameter name -> value
};

// The trailing checksum of a model file whose bytes before the checksum are `bytes`.
uint64_t model_file_checksum(std::string_view bytes);

void write_model_file(const std::filesystem::path& path, const ModelFileContents& contents);
ModelFileContents read_model_file(const std::filesystem::path& path);

struct Model {
  SRNetwork network{nullptr};
  Provenance provenance;
};

// Saves every parameter of `net` (including a geometry head) with its spec.
void save_model(const std::filesystem::path& path, const SRNetworkImpl& net, const Provenance& provenance = {});
Model load_model(const std::filesystem::path& path);

// True when the file starts with the model-file magic (cheap; does not validate the rest).
bool is_model_file(const std::filesystem::path& path);

}  // namespace cgsr
