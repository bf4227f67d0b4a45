#pragma once
// Model files: one self-describing file per trained network (extension .cgsr by convention).
//
//   offset  size  content
//   0       8     magic "CGSRMODL"
//   8       4     format version (little-endian uint32): 2 is written, 1 and 2 are read
//   12      8     metadata length M (little-endian uint64)
//   20      8     weights length W (little-endian uint64)
//   28      M     metadata: UTF-8 JSON {format, version, spec (YAML text), channels,
//                 provenance {stage, parent, config, metrics, extra},
//                 tensors [{name, dtype, shape}]}
//   28+M    W     weights: version 2: each tensor's values as raw little-endian float32
//                 (dtype "float32"), row-major, in the metadata's order, back to back; version 1:
//                 a torch::save archive of the tensors
//   28+M+W  8     FNV-1a 64 of every byte before it (little-endian); version 1 files used the
//                 offset basis 1469598103934665603 (a digit short of FNV-1a's) and keep it
//
// Files are written atomically. Reading is bounded by the file: it checks magic, version, the
// limits below, lengths (truncation) and the checksum (corruption) before it parses anything, then
// every tensor's declared shape (non-negative, at most kMaxTensorRank dimensions, an element count
// that fits the weight bytes left) before it allocates any tensor, then the spec (the same
// validation as a spec file). Version 1 weights are read without LibTorch's deserializer, which
// allocates what sizes inside the archive say: tensor i is the archive's stored record data/i,
// which must be exactly the size of the tensor's declared shape (cgsr wrote each tensor with its
// own storage, in the metadata's order). load_model then builds the spec's network with the stored
// values as its parameter budget and checks the weights are exactly its parameters. Every failure
// is a cgsr::Error naming the file (and the tensor, when one is at fault).

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/json_fields.h"
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

CGSR_JSON_FIELDS_WITH_DEFAULT(Provenance, stage, parent, config, metrics, extra)  // a missing key: its default
// A file's provenance object; an Error naming `context` when it is not one.
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

// What a model file may hold: a reader refuses (and the writer never writes) more.
inline constexpr uint64_t kMaxModelWeightBytes = uint64_t{1} << 31;    // 2 GiB of tensor values
inline constexpr uint64_t kMaxModelMetadataBytes = uint64_t{16} << 20;  // 16 MiB of JSON
inline constexpr size_t kMaxModelTensors = 65536;
inline constexpr size_t kMaxTensorRank = 8;

// The trailing checksum of a model file whose bytes before the checksum are `bytes`: FNV-1a 64,
// with the legacy basis when the version field in `bytes` says 1.
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
