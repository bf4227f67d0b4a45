#include "models/model_file.h"

#include <yaml-cpp/yaml.h>

#include <torch/torch.h>

#include <algorithm>
#include <climits>
#include <cstring>
#include <fstream>
#include <map>
#include <set>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/hash.h"
#include "core/tensor_checks.h"
#include "core/text.h"
#include "models/layers.h"

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

// Raw tensor values are copied as they lie in memory; the format says little-endian.
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "model files store little-endian float32: add byte swapping for this host"
#endif

constexpr char kMagic[8] = {'C', 'G', 'S', 'R', 'M', 'O', 'D', 'L'};
constexpr uint32_t kVersion = 2;        // written
constexpr uint32_t kOldestVersion = 1;  // still read
constexpr size_t kHeaderSize = 8 + 4 + 8 + 8;
constexpr size_t kChecksumSize = 8;
constexpr const char* kFloat32 = "float32";

template <class T>
void put_le(std::string& out, T value) {
  for (size_t i = 0; i < sizeof(T); ++i) out.push_back(static_cast<char>((value >> (8 * i)) & 0xff));
}

template <class T>
T get_le(std::string_view in, size_t offset) {
  T v = 0;
  for (size_t i = 0; i < sizeof(T); ++i) v |= static_cast<T>(static_cast<unsigned char>(in[offset + i])) << (8 * i);
  return v;
}

std::string shape_of(const std::vector<int64_t>& sizes) {
  std::string s = "[";
  for (size_t i = 0; i < sizes.size(); ++i) s += (i ? ", " : "") + std::to_string(sizes[i]);
  return s + "]";
}

// A tensor the metadata lists, its shape checked against the weight bytes.
struct DeclaredTensor {
  std::string name;
  std::vector<int64_t> shape;
  uint64_t bytes = 0;
};

// The metadata's tensor list, every entry checked before anything is allocated: a name, dtype
// float32 (version 2; version 1 stored float32 without saying so), at most kMaxTensorRank
// non-negative dimensions, and a size that fits the weight bytes the tensors before it left (in
// both versions tensors occupy disjoint bytes of the weights, so together they fit).
std::vector<DeclaredTensor> declared_tensors(const nlohmann::ordered_json& list, uint32_t version,
                                             uint64_t weight_size, const std::string& where) {
  if (!list.is_array()) throw Error(where, "malformed metadata: tensors is not a list");
  if (list.size() > kMaxModelTensors)
    throw Error(where, "metadata lists " + std::to_string(list.size()) + " tensors, more than the limit of " +
                           std::to_string(kMaxModelTensors));
  std::vector<DeclaredTensor> out;
  uint64_t left = weight_size;
  for (size_t i = 0; i < list.size(); ++i) {
    const auto& t = list[i];
    if (!t.is_object() || !t.contains("name") || !t["name"].is_string() || t["name"].get<std::string>().empty())
      throw Error(where, "malformed metadata: tensor " + std::to_string(i) + " has no name");
    DeclaredTensor d;
    d.name = t["name"].get<std::string>();
    const std::string what = "tensor " + d.name;
    if (version >= 2 && (!t.contains("dtype") || t["dtype"] != kFloat32))
      throw Error(where, what + ": dtype " + (t.contains("dtype") ? t["dtype"].dump() : "missing") + ", expected \"" +
                             kFloat32 + "\"");
    const auto shape = t.contains("shape") ? t["shape"] : nlohmann::ordered_json();
    if (!shape.is_array() || shape.size() > kMaxTensorRank)
      throw Error(where, what + ": shape must be a list of at most " + std::to_string(kMaxTensorRank) + " sizes");
    bool empty = false;
    for (const auto& n : shape) {
      // Unsigned JSON numbers above INT64_MAX are refused here rather than wrapped.
      if (!n.is_number_integer() || (n.is_number_unsigned() && n.get<uint64_t>() > uint64_t(INT64_MAX)) ||
          n.get<int64_t>() < 0)
        throw Error(where, what + ": shape " + shape.dump() + " holds something other than a size >= 0");
      d.shape.push_back(n.get<int64_t>());
      empty = empty || d.shape.back() == 0;
    }
    // Values the weights can still hold; multiplying up to it never overflows.
    const uint64_t room = left / sizeof(float);
    uint64_t elements = 1;
    for (const int64_t n : d.shape) {
      if (empty) {
        elements = 0;
        break;
      }
      if (static_cast<uint64_t>(n) > room / elements)
        throw Error(where, what + ": shape " + shape_of(d.shape) + " needs more than the " + std::to_string(left) +
                               " weight bytes the tensors before it left");
      elements *= static_cast<uint64_t>(n);
    }
    if (elements > room)  // a rank-0 tensor (one value) with no bytes left
      throw Error(where, what + ": shape " + shape_of(d.shape) + " needs more than the " + std::to_string(left) +
                             " weight bytes the tensors before it left");
    d.bytes = elements * sizeof(float);
    left -= d.bytes;
    out.push_back(std::move(d));
  }
  return out;
}

// A tensor of `shape` holding the little-endian float32 values at `bytes`.
torch::Tensor float_tensor(const std::vector<int64_t>& shape, std::string_view bytes) {
  torch::Tensor t = torch::empty(shape, torch::kFloat32);
  if (!bytes.empty()) std::memcpy(t.data_ptr<float>(), bytes.data(), bytes.size());
  return t;
}

// Version 2 weights: the declared tensors back to back, nothing after the last.
std::vector<torch::Tensor> read_raw_weights(std::string_view weights, const std::vector<DeclaredTensor>& declared,
                                            const std::string& where) {
  uint64_t total = 0;
  for (const auto& d : declared) total += d.bytes;  // declared_tensors kept the sum within the weights
  if (total != weights.size())
    throw Error(where, "the weights hold " + std::to_string(weights.size()) + " bytes, the tensors the metadata lists " +
                           std::to_string(total));
  std::vector<torch::Tensor> values;
  size_t at = 0;
  for (const auto& d : declared) {
    values.push_back(float_tensor(d.shape, weights.substr(at, d.bytes)));
    at += d.bytes;
  }
  return values;
}

// Version 1 weights, a torch::save archive (a ZIP file whose tensor records are stored
// uncompressed): tensor i is record <archive>/data/i. Only the ZIP directory is parsed, every
// offset and size against the archive's bounds; the pickled object graph is not interpreted.
std::vector<torch::Tensor> read_archive_weights(std::string_view zip, const std::vector<DeclaredTensor>& declared,
                                                const std::string& where) {
  const auto bad = [&](const std::string& what) { return Error(where, "version 1 weights archive: " + what); };
  constexpr size_t kEndSize = 22, kEntrySize = 46, kLocalSize = 30;
  if (zip.size() < kEndSize) throw bad("too short for a ZIP archive");
  // The end-of-central-directory record: last in the archive, before a comment of up to 64 KiB.
  size_t end = std::string_view::npos;
  for (size_t at = zip.size() - kEndSize + 1; at-- > 0 && zip.size() - at <= kEndSize + 0xffff;)
    if (get_le<uint32_t>(zip, at) == 0x06054b50) {
      end = at;
      break;
    }
  if (end == std::string_view::npos) throw bad("no ZIP directory");
  const uint64_t entries = get_le<uint16_t>(zip, end + 10), dir_offset = get_le<uint32_t>(zip, end + 16);
  std::map<size_t, std::string_view> records;  // data/<index> -> bytes
  uint64_t at = dir_offset;
  for (uint64_t e = 0; e < entries; ++e) {
    if (at > zip.size() || zip.size() - at < kEntrySize || get_le<uint32_t>(zip, at) != 0x02014b50)
      throw bad("ZIP directory entry " + std::to_string(e) + " is out of bounds or malformed");
    const uint16_t method = get_le<uint16_t>(zip, at + 10);
    const uint64_t size = get_le<uint32_t>(zip, at + 20), stored_size = get_le<uint32_t>(zip, at + 24);
    const uint64_t name_size = get_le<uint16_t>(zip, at + 28), extra = get_le<uint16_t>(zip, at + 30),
                   comment = get_le<uint16_t>(zip, at + 32), local = get_le<uint32_t>(zip, at + 42);
    if (zip.size() - at - kEntrySize < name_size) throw bad("ZIP directory entry " + std::to_string(e) + " is truncated");
    const std::string_view name = zip.substr(at + kEntrySize, name_size);
    at += kEntrySize + name_size + extra + comment;
    // Only "<archive>/data/<digits>" matters: the tensors' storages.
    const size_t slash = name.find('/');
    const std::string_view rest = slash == std::string_view::npos ? std::string_view() : name.substr(slash + 1);
    if (rest.size() <= 5 || rest.substr(0, 5) != "data/" || rest.size() > 5 + 9 ||
        !std::all_of(rest.begin() + 5, rest.end(), [](char c) { return c >= '0' && c <= '9'; }))
      continue;
    const std::string record(name);
    if (method != 0 || size != stored_size) throw bad("record " + record + " is compressed or its sizes disagree");
    if (local > zip.size() || zip.size() - local < kLocalSize || get_le<uint32_t>(zip, local) != 0x04034b50)
      throw bad("record " + record + " has no local header");
    const uint64_t data = local + kLocalSize + get_le<uint16_t>(zip, local + 26) + get_le<uint16_t>(zip, local + 28);
    if (data > zip.size() || zip.size() - data < size) throw bad("record " + record + " runs past the archive");
    const size_t index = std::stoul(std::string(rest.substr(5)));
    if (!records.emplace(index, zip.substr(data, size)).second) throw bad("record " + record + " is stored twice");
  }
  if (records.size() != declared.size())
    throw bad(std::to_string(records.size()) + " tensor records for the " + std::to_string(declared.size()) +
              " tensors the metadata lists");
  std::vector<torch::Tensor> values;
  for (size_t i = 0; i < declared.size(); ++i) {
    const auto it = records.find(i);
    if (it == records.end()) throw bad("no record data/" + std::to_string(i) + " for tensor " + declared[i].name);
    if (it->second.size() != declared[i].bytes)
      throw bad("record data/" + std::to_string(i) + " holds " + std::to_string(it->second.size()) + " bytes, tensor " +
                declared[i].name + " of shape " + shape_of(declared[i].shape) + " needs " +
                std::to_string(declared[i].bytes));
    values.push_back(float_tensor(declared[i].shape, it->second));
  }
  return values;
}

}  // namespace

uint64_t model_file_checksum(std::string_view bytes) {
  const bool version1 = bytes.size() >= 12 && get_le<uint32_t>(bytes, 8) == 1;
  return fnv1a64(bytes, version1 ? kLegacyFnv1a64Basis : kFnv1a64OffsetBasis);
}

Provenance provenance_from_json(const nlohmann::ordered_json& j, const std::string& context) {
  if (!j.is_object()) throw Error(context, "provenance must be a JSON object");
  try {
    return j.get<Provenance>();
  } catch (const nlohmann::json::exception& e) {
    throw Error(context, std::string("provenance: ") + e.what());
  }
}

void write_model_file(const std::filesystem::path& path, const ModelFileContents& contents) {
  nlohmann::ordered_json meta;
  meta["format"] = "cgsr-model";
  meta["version"] = kVersion;
  meta["spec"] = spec_to_yaml(contents.spec);
  meta["channels"] = channel_names(contents.spec.input_channels());
  meta["provenance"] = contents.provenance;
  const std::string where = path.string();
  if (contents.tensors.size() > kMaxModelTensors)
    throw Error(where, std::to_string(contents.tensors.size()) + " tensors, more than a model file holds (" +
                           std::to_string(kMaxModelTensors) + ")");
  auto tensors = nlohmann::ordered_json::array();
  std::string weight_bytes;
  for (const auto& [name, t] : contents.tensors) {
    // Parameters are float32 throughout cgsr; another dtype here is a caller's mistake.
    if (t.scalar_type() != torch::kFloat32)
      throw Error(where, "tensor " + name + " is " + std::string(c10::toString(t.scalar_type())) +
                             ", model files store float32");
    if (t.dim() > static_cast<int64_t>(kMaxTensorRank))
      throw Error(where, "tensor " + name + " has " + std::to_string(t.dim()) + " dimensions, more than " +
                             std::to_string(kMaxTensorRank));
    const torch::Tensor values = t.detach().cpu().contiguous();
    const size_t bytes = values.numel() * sizeof(float);
    if (weight_bytes.size() + bytes > kMaxModelWeightBytes)
      throw Error(where, "the weights exceed the model file limit of " + std::to_string(kMaxModelWeightBytes) +
                             " bytes at tensor " + name);
    tensors.push_back({{"name", name}, {"dtype", kFloat32}, {"shape", t.sizes().vec()}});
    weight_bytes.append(reinterpret_cast<const char*>(values.data_ptr<float>()), bytes);
  }
  meta["tensors"] = tensors;
  const std::string meta_text = meta.dump(1);
  if (meta_text.size() > kMaxModelMetadataBytes)
    throw Error(where, "metadata of " + std::to_string(meta_text.size()) + " bytes exceeds the model file limit of " +
                           std::to_string(kMaxModelMetadataBytes));

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
  // Refused before it is read: no file within the limits is larger.
  constexpr uint64_t kMaxFileSize = kHeaderSize + kMaxModelMetadataBytes + kMaxModelWeightBytes + kChecksumSize;
  std::error_code ec;
  const uint64_t on_disk = std::filesystem::file_size(path, ec);
  if (!ec && on_disk > kMaxFileSize)
    throw Error(where, "model file of " + std::to_string(on_disk) + " bytes exceeds the limit of " +
                           std::to_string(kMaxFileSize));
  const std::string file = read_file(path);
  if (file.size() < sizeof kMagic || std::memcmp(file.data(), kMagic, sizeof kMagic) != 0)
    throw Error(where, "not a cgsr model file (bad magic)");
  if (file.size() < kHeaderSize + kChecksumSize)
    throw Error(where, "truncated model file: " + std::to_string(file.size()) + " bytes, shorter than its header");
  const uint32_t version = get_le<uint32_t>(file, 8);
  if (version < kOldestVersion || version > kVersion)
    throw Error(where, "model file format version " + std::to_string(version) + " is not supported (this cgsr reads " +
                           std::to_string(kOldestVersion) + " to " + std::to_string(kVersion) + ")");
  const uint64_t meta_size = get_le<uint64_t>(file, 12), weight_size = get_le<uint64_t>(file, 20);
  if (meta_size > kMaxModelMetadataBytes)
    throw Error(where, "the header announces " + std::to_string(meta_size) + " bytes of metadata, more than the limit of " +
                           std::to_string(kMaxModelMetadataBytes));
  if (weight_size > kMaxModelWeightBytes)
    throw Error(where, "the header announces " + std::to_string(weight_size) + " bytes of weights, more than the limit of " +
                           std::to_string(kMaxModelWeightBytes));
  const uint64_t body = kHeaderSize + meta_size + weight_size;  // no overflow: both sizes are capped
  if (body + kChecksumSize > file.size())
    throw Error(where, "truncated model file: the header announces " + std::to_string(body + kChecksumSize) +
                           " bytes, the file has " + std::to_string(file.size()));
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
  std::vector<DeclaredTensor> declared;
  try {
    if (meta.at("format") != "cgsr-model") throw Error(where, "metadata format is not cgsr-model");
    contents.spec = spec_from_yaml(with_legacy_defaults(meta.at("spec").get<std::string>()), where + " (spec)");
    contents.provenance = provenance_from_json(meta.value("provenance", nlohmann::ordered_json::object()), where);
    declared = declared_tensors(meta.at("tensors"), version, weight_size, where);
  } catch (const nlohmann::json::exception& e) {
    throw Error(where, std::string("malformed metadata: ") + e.what());
  }
  const std::string_view weights = std::string_view(file).substr(kHeaderSize + meta_size, weight_size);
  const std::vector<torch::Tensor> values = version == 1 ? read_archive_weights(weights, declared, where)
                                                         : read_raw_weights(weights, declared, where);
  for (size_t i = 0; i < values.size(); ++i) contents.tensors.emplace_back(declared[i].name, values[i]);
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
  {
    // Twice what the file stores, plus 4 MiB: a spec a little off its weights (a missing tensor, a
    // wider group) still gets the precise message below; widths that would allocate gigabytes do not.
    int64_t stored = 0;  // bounded by kMaxModelWeightBytes
    for (const auto& [name, value] : contents.tensors)
      if (name.rfind(kExtraTensorPrefix, 0) != 0) stored += value.numel();
    const ParameterBudget budget(2 * stored + (int64_t{1} << 20), where);
    model.network = SRNetwork(contents.spec);
  }
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
