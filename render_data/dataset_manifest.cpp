#include "render_data/dataset_manifest.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/atomic_file.h"
#include "core/config.h"
#include "core/error.h"
#include "core/text.h"

namespace cgsr {
namespace fs = std::filesystem;

Resolution parse_resolution(const std::string& text, const std::string& context) {
  const auto [w, h] = parse_size(text, context);
  return {w, h};
}

namespace {
struct KindInfo {
  FileKind kind;
  std::string name, extension, encoding;
};
const std::vector<KindInfo>& kinds() {
  static const std::vector<KindInfo> k = {
      {FileKind::Color, "color", ".png", "8-bit sRGB RGB PNG, values / 255 in [0,1]"},
      {FileKind::Depth, "depth", ".exr", "32-bit float EXR, linear view depth in metres; 0 = no geometry (sky, +inf)"},
      {FileKind::Normal, "normal", ".png", "16-bit RGB PNG of (n + 1) / 2, view-space unit normal; sky: see depth"},
      {FileKind::NormalAngle, "normal_angle", ".png", "16-bit grey PNG, angle to the camera / 90 degrees"},
      {FileKind::Edge, "edge", ".png", "8-bit grey PNG, 0 or 255"},
      {FileKind::Id, "id", ".png", "16-bit RGB PNG: R = object id + 1, G = material id + 1, B = 0; 0 = sky"},
      {FileKind::Motion, "motion", ".exr", "32-bit float EXR (dx, dy, 0) in pixels: the pixel was at p + (dx, dy)"},
  };
  return k;
}
const KindInfo& kind_info(FileKind k) { return kinds()[static_cast<size_t>(k)]; }
}  // namespace

const std::vector<FileKind>& all_file_kinds() {
  static const std::vector<FileKind> all = [] {
    std::vector<FileKind> v;
    for (const auto& k : kinds()) v.push_back(k.kind);
    return v;
  }();
  return all;
}
const std::string& file_kind_name(FileKind kind) { return kind_info(kind).name; }
const std::string& file_kind_extension(FileKind kind) { return kind_info(kind).extension; }
const std::string& file_kind_encoding(FileKind kind) { return kind_info(kind).encoding; }

const std::string& split_name(Split split) {
  static const std::string names[] = {"train", "val", "test", "all"};
  return names[static_cast<int>(split)];
}

Split split_from_name(const std::string& name) {
  const std::vector<std::string> names = {"train", "val", "test", "all"};
  for (size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<Split>(i);
  throw Error("split", "unknown split '" + name + "'" + did_you_mean(name, names) + "; valid: " + join(names));
}

const std::vector<int>& FrameSplit::of(Split split) const {
  switch (split) {
    case Split::Train: return train;
    case Split::Val: return val;
    case Split::Test: return test;
    default: break;
  }
  throw Error("split", "Split::All has no single frame list", ErrorKind::Internal);
}

FrameSplit make_split(int frames, double test_fraction, double val_fraction) {
  FrameSplit s;
  if (frames < 3) {
    for (int i = 0; i < frames; ++i) s.train.push_back(i);
    return s;
  }
  const int n_test = std::max(1, static_cast<int>(std::lround(frames * test_fraction)));
  const int n_val = std::max(1, static_cast<int>(std::lround(frames * val_fraction)));
  std::vector<char> role(frames, 'r');
  for (int k = 0; k < n_test; ++k)
    role[std::min(frames - 1, static_cast<int>((k + 0.5) * frames / n_test))] = 't';
  std::vector<int> rest;
  for (int i = 0; i < frames; ++i)
    if (role[i] == 'r') rest.push_back(i);
  const int m = static_cast<int>(rest.size());
  for (int k = 0; k < n_val && k < m - 1; ++k) role[rest[std::min(m - 1, static_cast<int>((k + 0.5) * m / n_val))]] = 'v';
  for (int i = 0; i < frames; ++i) (role[i] == 't' ? s.test : role[i] == 'v' ? s.val : s.train).push_back(i);
  return s;
}

fs::path frame_file(const fs::path& root, const Resolution& resolution, FileKind kind, int frame) {
  char name[32];
  std::snprintf(name, sizeof name, "%06d", frame);
  return root / resolution.name() / file_kind_name(kind) / (std::string(name) + file_kind_extension(kind));
}

fs::path DatasetManifest::file(const fs::path& root, int frame, size_t resolution, FileKind kind) const {
  return frame_file(root, resolutions.at(resolution), kind, frame);
}

bool has_manifest(const fs::path& root) { return fs::exists(root / "manifest.yaml"); }

void write_manifest(const fs::path& root, const DatasetManifest& m) {
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "format" << YAML::Value << DatasetManifest::kFormat;
  out << YAML::Key << "version" << YAML::Value << DatasetManifest::kVersion;
  out << YAML::Key << "name" << YAML::Value << m.name;
  out << YAML::Key << "complete" << YAML::Value << m.complete;
  out << YAML::Key << "fingerprint" << YAML::Value << m.fingerprint;
  out << YAML::Key << "frames" << YAML::Value << m.frames;
  out << YAML::Key << "resolutions" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (const auto& r : m.resolutions) out << r.name();
  out << YAML::EndSeq;
  out << YAML::Key << "near" << YAML::Value << m.near_plane;
  out << YAML::Key << "far" << YAML::Value << m.far_plane;
  out << YAML::Key << "vfov" << YAML::Value << m.vfov;
  out << YAML::Key << "scene_source" << YAML::Value << m.scene_source;
  out << YAML::Key << "seed" << YAML::Value << m.seed;
  out << YAML::Key << "files" << YAML::Value << YAML::BeginMap;
  for (FileKind k : all_file_kinds()) {
    out << YAML::Key << file_kind_name(k) << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "path" << YAML::Value << "<resolution>/" + file_kind_name(k) + "/<frame:06d>" + file_kind_extension(k);
    out << YAML::Key << "encoding" << YAML::Value << file_kind_encoding(k);
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  out << YAML::Key << "split" << YAML::Value << YAML::BeginMap;
  for (Split s : {Split::Train, Split::Val, Split::Test}) {
    out << YAML::Key << split_name(s) << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (int f : m.split.of(s)) out << f;
    out << YAML::EndSeq;
  }
  out << YAML::EndMap;
  if (!m.bytes_per_frame.empty()) {
    out << YAML::Key << "bytes_per_frame" << YAML::Value << YAML::BeginMap;
    for (size_t i = 0; i < m.resolutions.size() && i < m.bytes_per_frame.size(); ++i)
      out << YAML::Key << m.resolutions[i].name() << YAML::Value << static_cast<int64_t>(std::llround(m.bytes_per_frame[i]));
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  write_file_atomic(root / "manifest.yaml", std::string(out.c_str()) + "\n");
}

DatasetManifest read_manifest(const fs::path& root) {
  const fs::path path = root / "manifest.yaml";
  if (!fs::exists(path)) throw Error(path.string(), "no manifest.yaml: not a cgsr dataset directory");
  const auto doc = config::Document::load_file(path);
  const YAML::Node& n = doc.root();
  const config::Cursor at{&doc, ""};
  if (!n.IsMap()) at.fail(n, "expected a map of keys, got " + config::detail::describe(n));
  auto need = [&](const char* key) {
    if (!n[key]) at.child(key).fail(n, std::string("missing required key '") + key + "'");
    return n[key];
  };
  DatasetManifest m;
  const auto format = config::Codec<std::string>::decode(need("format"), at.child("format"));
  if (format != DatasetManifest::kFormat) at.child("format").fail(n["format"], "expected '" + std::string(DatasetManifest::kFormat) + "'");
  const int version = config::Codec<int>::decode(need("version"), at.child("version"));
  if (version != DatasetManifest::kVersion) at.child("version").fail(n["version"], "unsupported version " + std::to_string(version));
  m.name = config::Codec<std::string>::decode(need("name"), at.child("name"));
  m.complete = config::Codec<bool>::decode(need("complete"), at.child("complete"));
  m.fingerprint = config::Codec<std::string>::decode(need("fingerprint"), at.child("fingerprint"));
  m.frames = config::Codec<int>::decode(need("frames"), at.child("frames"));
  if (m.frames < 1) at.child("frames").fail(n["frames"], "must be at least 1");
  for (const auto& r : config::Codec<std::vector<std::string>>::decode(need("resolutions"), at.child("resolutions")))
    m.resolutions.push_back(parse_resolution(r, doc.locate(n["resolutions"]) + ": resolutions"));
  if (m.resolutions.empty()) at.child("resolutions").fail(n["resolutions"], "needs at least one resolution");
  m.near_plane = config::Codec<double>::decode(need("near"), at.child("near"));
  m.far_plane = config::Codec<double>::decode(need("far"), at.child("far"));
  if (!(m.near_plane > 0) || !(m.far_plane > m.near_plane)) at.child("far").fail(n["far"], "need 0 < near < far");
  if (n["vfov"]) m.vfov = config::Codec<double>::decode(n["vfov"], at.child("vfov"));
  if (n["scene_source"]) m.scene_source = config::Codec<std::string>::decode(n["scene_source"], at.child("scene_source"));
  if (n["seed"]) m.seed = config::Codec<uint64_t>::decode(n["seed"], at.child("seed"));
  const YAML::Node split = need("split");
  const config::Cursor sat = at.child("split");
  if (!split.IsMap()) sat.fail(split, "expected a map of train, val and test frames, got " + config::detail::describe(split));
  for (Split s : {Split::Train, Split::Val, Split::Test}) {
    const auto key = split_name(s);
    if (!split[key]) sat.child(key).fail(split, "missing required key '" + key + "'");
    auto& list = const_cast<std::vector<int>&>(m.split.of(s));
    list = config::Codec<std::vector<int>>::decode(split[key], sat.child(key));
    for (int f : list)
      if (f < 0 || f >= m.frames) sat.child(key).fail(split[key], "frame " + std::to_string(f) + " out of range");
  }
  if (const YAML::Node bytes = n["bytes_per_frame"]) {
    const config::Cursor bat = at.child("bytes_per_frame");
    if (!bytes.IsMap()) bat.fail(bytes, "expected a map from resolution to bytes, got " + config::detail::describe(bytes));
    for (const auto& r : m.resolutions)
      m.bytes_per_frame.push_back(bytes[r.name()] ? config::Codec<double>::decode(bytes[r.name()], bat.child(r.name())) : 0.0);
  }
  for (size_t i = 1; i < m.resolutions.size(); ++i)
    if (m.resolutions[i].width <= m.resolutions[i - 1].width)
      at.child("resolutions").fail(n["resolutions"], "resolutions must be listed in ascending order");
  return m;
}

}  // namespace cgsr
