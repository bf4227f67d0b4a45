#include "models/model_file.h"

#include <yaml-cpp/yaml.h>

#include <torch/torch.h>

#include <algorithm>
#include <cstring>
#include <set>
#include <fstream>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/tensor_checks.h"
#include "core/text.h"

namespace cgsr {
namespace {

// Keys added to the spec since a file was written get the value that reproduces the old
// behaviour: files from before rit.depth_encoding fed the network z-buffer depth.
std::string with_legacy_defaults(const std::string& spec_yaml) {
  try {
    YAML::Node spec = YAML::Load(spec_yaml);
    if (!spec.IsMap() || !spec["rit"] || !spec["rit"].IsMap() || spec["rit"]["depth_encoding"]) return spec_yaml;
    spec["rit"]["depth_encoding"] = "zbuffer";
    return YAML::Dump(spec);
  } catch (const YAML::Exception&) {
    return spec_yaml;  // spec_from_yaml reports where it is malformed
  }
}

constexpr char kMagic[8] = {'C', 'G', 'S', 'R', 'M', 'O', 'D', 'L'};
constexpr uint32_t kVersion = 1;
constexpr size_t kHeaderSize = 8 + 4 + 8 + 8;
constexpr size_t kChecksumSize = 8;

template <class T>
void put_le(std::string& out, T value) {
  for (size_t i = 0; i < sizeof(T); ++i) out.push_back(static_cast<char>((value >> (8 * i)) & 0xff));
}

template <class T>
T get_le(const std::string& in, size_t offset) {
  T v = 0;
  for (size_t i = 0; i < sizeof(T); ++i) v |= static_cast<T>(static_cast<unsigned char>(in[offset + i])) << (8 * i);
  return v;
}

std::string shape_of(const std::vector<int64_t>& sizes) {
  std::string s = "[";
  for (size_t i = 0; i < sizes.size(); ++i) s += (i ? ", " : "") + std::to_string(sizes[i]);
  return s + "]";
}

}  // namespace

uint64_t model_file_checksum(std::string_view bytes) {
  uint64_t h = 1469598103934665603ull;  // FNV-1a, 64 bit
  for (const char c : bytes) {
    h ^= static_cast<unsigned char>(c);
    h *= 1099511628211ull;
  }
  return h;
}

nlohmann::ordered_json to_json(const Provenance& p) {
  nlohmann::ordered_json j;
  j["stage"] = p.stage;
  j["parent"] = p.parent;
  j["config"] = p.config;
  j["metrics"] = p.metrics;
  j["extra"] = p.extra;
  return j;
}

Provenance provenance_from_json(const nlohmann::ordered_json& j, const std::string& context) {
  if (!j.is_object()) throw Error(context, "provenance must be a JSON object");
  Provenance p;
  try {
    p.stage = j.value("stage", std::string());
    p.parent = j.value("parent", std::string());
  } catch (const nlohmann::json::exception& e) {
    throw Error(context, std::string("provenance: ") + e.what());
  }
  if (j.contains("config")) p.config = j["config"];
  if (j.contains("metrics")) p.metrics = j["metrics"];
  if (j.contains("extra")) p.extra = j["extra"];
  return p;
}

void write_model_file(const std::filesystem::path& path, const ModelFileContents& contents) {
  nlohmann::ordered_json meta;
  meta["format"] = "cgsr-model";
  meta["version"] = kVersion;
  meta["spec"] = spec_to_yaml(contents.spec);
  meta["channels"] = channel_names(contents.spec.input_channels());
  meta["provenance"] = to_json(contents.provenance);
  auto tensors = nlohmann::ordered_json::array();
  std::vector<torch::Tensor> values;
  for (const auto& [name, t] : contents.tensors) {
    tensors.push_back({{"name", name}, {"shape", t.sizes().vec()}});
    values.push_back(t.detach().contiguous().cpu());
  }
  meta["tensors"] = tensors;
  const std::string meta_text = meta.dump(1);
  std::ostringstream weights;
  torch::save(values, weights);
  const std::string weight_bytes = weights.str();

  std::string file(kMagic, sizeof kMagic);
  put_le<uint32_t>(file, kVersion);
  put_le<uint64_t>(file, meta_text.size());
  put_le<uint64_t>(file, weight_bytes.size());
  file += meta_text;
  file += weight_bytes;
  put_le<uint64_t>(file, model_file_checksum(file));
  write_file_atomic(path, file);
}

ModelFileContents read_model_file(const std::filesystem::path& path) {
  const std::string where = path.string();
  if (!std::filesystem::exists(path)) throw Error(where, "no such model file");
  const std::string file = read_file(path);
  if (file.size() < sizeof kMagic || std::memcmp(file.data(), kMagic, sizeof kMagic) != 0)
    throw Error(where, "not a cgsr model file (bad magic)");
  if (file.size() < kHeaderSize + kChecksumSize)
    throw Error(where, "truncated model file: " + std::to_string(file.size()) + " bytes, shorter than its header");
  const uint32_t version = get_le<uint32_t>(file, 8);
  if (version != kVersion)
    throw Error(where, "model file format version " + std::to_string(version) + " is not supported (this cgsr reads " +
                           std::to_string(kVersion) + ")");
  const uint64_t meta_size = get_le<uint64_t>(file, 12), weight_size = get_le<uint64_t>(file, 20);
  const uint64_t limit = file.size();
  if (meta_size > limit || weight_size > limit || kHeaderSize + meta_size + weight_size + kChecksumSize > limit)
    throw Error(where, "truncated model file: the header announces " +
                           std::to_string(kHeaderSize + meta_size + weight_size + kChecksumSize) + " bytes, the file has " +
                           std::to_string(file.size()));
  const size_t body = kHeaderSize + meta_size + weight_size;
  if (body + kChecksumSize != file.size())
    throw Error(where, std::to_string(file.size() - body - kChecksumSize) + " unexpected bytes after the model data");
  if (get_le<uint64_t>(file, body) != model_file_checksum(std::string_view(file).substr(0, body)))
    throw Error(where, "corrupted model file (checksum mismatch)");

  nlohmann::ordered_json meta;
  try {
    meta = nlohmann::ordered_json::parse(file.substr(kHeaderSize, meta_size));
  } catch (const nlohmann::json::exception& e) {
    throw Error(where, std::string("unreadable metadata: ") + e.what());
  }
  ModelFileContents contents;
  std::vector<std::pair<std::string, std::vector<int64_t>>> declared;
  try {
    if (meta.at("format") != "cgsr-model") throw Error(where, "metadata format is not cgsr-model");
    contents.spec = spec_from_yaml(with_legacy_defaults(meta.at("spec").get<std::string>()), where + " (spec)");
    contents.provenance = provenance_from_json(meta.value("provenance", nlohmann::ordered_json::object()), where);
    for (const auto& t : meta.at("tensors"))
      declared.emplace_back(t.at("name").get<std::string>(), t.at("shape").get<std::vector<int64_t>>());
  } catch (const nlohmann::json::exception& e) {
    throw Error(where, std::string("malformed metadata: ") + e.what());
  }
  std::vector<torch::Tensor> values;
  try {
    std::istringstream in(file.substr(kHeaderSize + meta_size, weight_size));
    torch::load(values, in);
  } catch (const c10::Error& e) {
    throw Error(where, "unreadable weights: " + std::string(e.what_without_backtrace()));
  } catch (const std::exception& e) {  // the TorchScript deserializer also throws its own errors
    throw Error(where, "unreadable weights: " + std::string(e.what()));
  }
  if (values.size() != declared.size())
    throw Error(where, "metadata lists " + std::to_string(declared.size()) + " tensors, the weights hold " +
                           std::to_string(values.size()));
  for (size_t i = 0; i < values.size(); ++i) {
    if (values[i].sizes().vec() != declared[i].second)
      throw Error(where, "tensor " + declared[i].first + " is " + shape_string(values[i]) + ", metadata says " +
                             shape_of(declared[i].second));
    contents.tensors.emplace_back(declared[i].first, values[i]);
  }
  const auto expected = channel_names(contents.spec.input_channels());
  if (meta.contains("channels")) {
    const auto& channels = meta["channels"];
    const bool strings = channels.is_array() && std::all_of(channels.begin(), channels.end(),
                                                              [](const auto& c) { return c.is_string(); });
    if (!strings || channels.get<std::vector<std::string>>() != expected)
      throw Error(where, "metadata channels do not match the spec's rit.channels (" + join(expected) + ")");
  }
  return contents;
}

void save_model(const std::filesystem::path& path, const SRNetworkImpl& net, const Provenance& provenance) {
  ModelFileContents contents;
  contents.spec = net.spec();
  contents.provenance = provenance;
  for (const auto& p : net.named_parameters(/*recurse=*/true)) contents.tensors.emplace_back(p.key(), p.value());
  write_model_file(path, contents);
}

Model load_model(const std::filesystem::path& path) {
  const std::string where = path.string();
  ModelFileContents contents = read_model_file(path);
  Model model;
  model.network = SRNetwork(contents.spec);
  model.provenance = contents.provenance;
  auto params = model.network->named_parameters(/*recurse=*/true);
  std::set<std::string> seen;
  torch::NoGradGuard no_grad;
  for (const auto& [name, value] : contents.tensors) {
    if (name.rfind(kExtraTensorPrefix, 0) == 0) continue;
    torch::Tensor* target = params.find(name);
    if (!target)
      throw Error(where, "weights do not match the spec (" + spec_summary(contents.spec) + "): unexpected tensor " +
                             name);
    if (target->sizes() != value.sizes())
      throw Error(where, "weights do not match the spec (" + spec_summary(contents.spec) + "): " + name + " is " +
                             shape_string(value) + ", the spec needs " + shape_string(*target));
    if (!seen.insert(name).second) throw Error(where, "tensor " + name + " is stored twice");
    require_finite(value, where + ": " + name);
    target->copy_(value);
  }
  for (const auto& p : params)
    if (!seen.count(p.key()))
      throw Error(where, "weights do not match the spec (" + spec_summary(contents.spec) + "): missing tensor " +
                             p.key());
  return model;
}

bool is_model_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  char head[sizeof kMagic] = {};
  return in.read(head, sizeof head) && std::memcmp(head, kMagic, sizeof kMagic) == 0;
}

}  // namespace cgsr
