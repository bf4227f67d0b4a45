#include "render_data/dataset_manifest.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/atomic_file.h"
#include "core/config.h"
#include "core/error.h"
#include "core/hash.h"
#include "core/image_header.h"
#include "core/text.h"
#include "render_data/hr_samples.h"

namespace cgsr {
namespace fs = std::filesystem;

Resolution parse_resolution(const std::string& text, const std::string& context) {
  const auto [w, h] = parse_size(text, context);
  // A frame must be an image cgsr reads back (core/image_header.h); a larger one would also
  // exhaust memory while it renders.
  const std::string at = "resolution " + text + ": ";
  if (w > kMaxImageSide) throw Error(context, at + "width " + config::out_of_range(w, 1, kMaxImageSide));
  if (h > kMaxImageSide) throw Error(context, at + "height " + config::out_of_range(h, 1, kMaxImageSide));
  if (int64_t{w} * h > kMaxImagePixels)
    throw Error(context, at + "pixel count " + config::out_of_range(static_cast<double>(int64_t{w} * h), 1, kMaxImagePixels));
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

std::string hex_fingerprint(const std::string& text) {
  const uint64_t h = fnv1a64(text, kLegacyFnv1a64Basis);  // legacy basis: existing data set fingerprints stay valid
  char buf[20];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

namespace {
void write_split(YAML::Emitter& out, const FrameSplit& split) {
  out << YAML::Key << "split" << YAML::Value << YAML::BeginMap;
  for (Split s : {Split::Train, Split::Val, Split::Test}) {
    out << YAML::Key << split_name(s) << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (int f : split.of(s)) out << f;
    out << YAML::EndSeq;
  }
  out << YAML::EndMap;
}
}  // namespace

void write_manifest(const fs::path& root, const DatasetManifest& m) {
  const bool multi = !m.scenes.empty();
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "format" << YAML::Value << DatasetManifest::kFormat;
  // A single scene stays version 1, readable by builds that predate scenes.
  out << YAML::Key << "version" << YAML::Value << (multi ? DatasetManifest::kVersion : DatasetManifest::kSingleSceneVersion);
  out << YAML::Key << "name" << YAML::Value << m.name;
  out << YAML::Key << "complete" << YAML::Value << m.complete;
  out << YAML::Key << "fingerprint" << YAML::Value << m.fingerprint;
  out << YAML::Key << "frames" << YAML::Value << m.frames;
  out << YAML::Key << "resolutions" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (const auto& r : m.resolutions) out << r.name();
  out << YAML::EndSeq;
  if (multi) {
    out << YAML::Key << "scenes" << YAML::Value << YAML::BeginSeq;
    for (const auto& sc : m.scenes) {
      out << YAML::Flow << YAML::BeginMap;
      out << YAML::Key << "name" << YAML::Value << sc.name;
      out << YAML::Key << "path" << YAML::Value << sc.path;
      out << YAML::Key << "first_frame" << YAML::Value << sc.first_frame;
      out << YAML::Key << "frames" << YAML::Value << sc.frames;
      if (sc.weight > 0) out << YAML::Key << "weight" << YAML::Value << sc.weight;
      out << YAML::Key << "fingerprint" << YAML::Value << sc.fingerprint;
      out << YAML::EndMap;
    }
    out << YAML::EndSeq;
    write_split(out, m.split);
    out << YAML::EndMap;
    write_file_atomic(root / "manifest.yaml", std::string(out.c_str()) + "\n");
    return;
  }
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
  if (m.bsp_border_depth > 0) {
    out << YAML::Key << "bsp_border" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "resolution" << YAML::Value << m.resolutions.front().name();
    out << YAML::Key << "depth" << YAML::Value << m.bsp_border_depth;
    out << YAML::Key << "samples" << YAML::Value << m.bsp_border_samples;
    out << YAML::Key << "path" << YAML::Value << "<resolution>/bsp_border/<frame:06d>.bsp";
    out << YAML::Key << "encoding" << YAML::Value << "cgsr sub-pixel BSP border file version 1 (docs/bsp_border.md)";
    out << YAML::EndMap;
  }
  if (m.hr_samples > 1) {
    out << YAML::Key << "hr_samples" << YAML::Value << m.hr_samples;
    out << YAML::Key << "hr_filter" << YAML::Value << m.hr_filter;
  }
  if (!m.jitter_sequence.empty()) {
    out << YAML::Key << "jitter" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "resolution" << YAML::Value << m.resolutions.front().name();
    out << YAML::Key << "sequence" << YAML::Value << m.jitter_sequence;
    out << YAML::Key << "phases" << YAML::Value << m.jitter_phases;
    out << YAML::Key << "offsets" << YAML::Value << YAML::BeginSeq;
    for (const auto& o : m.jitter_offsets) out << YAML::Flow << YAML::BeginSeq << o[0] << o[1] << YAML::EndSeq;
    out << YAML::EndSeq << YAML::EndMap;
  }
  write_split(out, m.split);
  if (!m.bytes_per_frame.empty()) {
    out << YAML::Key << "bytes_per_frame" << YAML::Value << YAML::BeginMap;
    for (size_t i = 0; i < m.resolutions.size() && i < m.bytes_per_frame.size(); ++i)
      out << YAML::Key << m.resolutions[i].name() << YAML::Value << static_cast<int64_t>(std::llround(m.bytes_per_frame[i]));
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  write_file_atomic(root / "manifest.yaml", std::string(out.c_str()) + "\n");
}

namespace {
void read_scenes(const YAML::Node& list, const config::Cursor& at, DatasetManifest& m) {
  if (!list.IsSequence() || list.size() == 0)
    at.fail(list, "expected a non-empty list of scenes, got " + config::detail::describe(list));
  int next = 0;
  for (size_t i = 0; i < list.size(); ++i) {
    const YAML::Node e = list[i];
    const config::Cursor eat = at.index(i);
    if (!e.IsMap()) eat.fail(e, "expected a map {name, path, first_frame, frames, fingerprint}, got " + config::detail::describe(e));
    auto need = [&](const char* key) {
      if (!e[key]) eat.child(key).fail(e, std::string("missing required key '") + key + "'");
      return e[key];
    };
    ManifestScene sc;
    sc.name = config::Codec<std::string>::decode(need("name"), eat.child("name"));
    sc.path = config::Codec<std::string>::decode(need("path"), eat.child("path"));
    sc.fingerprint = config::Codec<std::string>::decode(need("fingerprint"), eat.child("fingerprint"));
    sc.first_frame = config::Codec<int>::decode(need("first_frame"), eat.child("first_frame"));
    sc.frames = config::Codec<int>::decode(need("frames"), eat.child("frames"));
    if (e["weight"]) sc.weight = config::Codec<double>::decode(e["weight"], eat.child("weight"));
    if (sc.name.empty()) eat.child("name").fail(e["name"], "must not be empty");
    if (sc.path.empty()) eat.child("path").fail(e["path"], "must not be empty");
    config::detail::require_in_range(sc.frames, 1, config::kUnbounded, e["frames"], eat.child("frames"));
    if (sc.first_frame != next)
      eat.child("first_frame").fail(e["first_frame"], "must be " + std::to_string(next) + " (the frames of the scenes before)");
    if (e["weight"]) config::detail::require_in_range(sc.weight, 0, config::kUnbounded, e["weight"], eat.child("weight"));
    for (const auto& other : m.scenes)
      if (other.name == sc.name) eat.child("name").fail(e["name"], "scene '" + sc.name + "' is listed twice");
    next += sc.frames;
    m.scenes.push_back(sc);
  }
  if (next != m.frames)
    at.fail(list, "the scenes have " + std::to_string(next) + " frames, the manifest says " + std::to_string(m.frames));
  const auto weighted = std::count_if(m.scenes.begin(), m.scenes.end(), [](const ManifestScene& s) { return s.weight > 0; });
  if (weighted != 0 && weighted != static_cast<long>(m.scenes.size()))
    at.fail(list, "give every scene a weight, or none (then scenes are drawn in proportion to their training frames)");
}
}  // namespace

namespace {
// The `jitter` block: offsets of the smallest resolution's frames, one per frame, in [-0.5, 0.5).
void read_jitter(const YAML::Node& n, const config::Cursor& at, DatasetManifest& m) {
  if (!n.IsMap()) at.fail(n, "expected a map {resolution, sequence, phases, offsets}, got " + config::detail::describe(n));
  for (const char* key : {"resolution", "sequence", "phases", "offsets"})
    if (!n[key]) at.child(key).fail(n, std::string("missing required key '") + key + "'");
  const auto resolution = config::Codec<std::string>::decode(n["resolution"], at.child("resolution"));
  if (resolution != m.resolutions.front().name())
    at.child("resolution").fail(n["resolution"], "is " + resolution + ", but only the smallest resolution, " +
                                                     m.resolutions.front().name() + ", is jittered");
  m.jitter_sequence = config::Codec<std::string>::decode(n["sequence"], at.child("sequence"));
  if (m.jitter_sequence != "halton")
    at.child("sequence").fail(n["sequence"], "unknown jitter sequence '" + m.jitter_sequence + "' (known: halton)");
  m.jitter_phases = config::Codec<int>::decode(n["phases"], at.child("phases"));
  config::detail::require_in_range(m.jitter_phases, 1, 1024, n["phases"], at.child("phases"));
  const auto offsets = config::Codec<std::vector<std::vector<double>>>::decode(n["offsets"], at.child("offsets"));
  if (static_cast<int>(offsets.size()) != m.frames)
    at.child("offsets").fail(n["offsets"], "has " + std::to_string(offsets.size()) + " offsets for " +
                                               std::to_string(m.frames) + " frames (one [x, y] per frame)");
  for (size_t f = 0; f < offsets.size(); ++f) {
    const auto& o = offsets[f];
    const config::Cursor fat = at.child("offsets").child(std::to_string(f));
    if (o.size() != 2) fat.fail(n["offsets"][f], "expected [x, y], got " + std::to_string(o.size()) + " numbers");
    for (double v : o)
      if (!(v >= -0.5 && v < 0.5)) fat.fail(n["offsets"][f], "offset " + std::to_string(v) + " is outside [-0.5, 0.5) pixels");
    m.jitter_offsets.push_back({o[0], o[1]});
  }
}
}  // namespace

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
  if (version < DatasetManifest::kSingleSceneVersion || version > DatasetManifest::kVersion)
    at.child("version").fail(n["version"], "unsupported version " + std::to_string(version) + " (this build reads 1 to " +
                                               std::to_string(DatasetManifest::kVersion) + ")");
  m.name = config::Codec<std::string>::decode(need("name"), at.child("name"));
  m.complete = config::Codec<bool>::decode(need("complete"), at.child("complete"));
  m.fingerprint = config::Codec<std::string>::decode(need("fingerprint"), at.child("fingerprint"));
  m.frames = config::Codec<int>::decode(need("frames"), at.child("frames"));
  config::detail::require_in_range(m.frames, 1, config::kUnbounded, n["frames"], at.child("frames"));
  for (const auto& r : config::Codec<std::vector<std::string>>::decode(need("resolutions"), at.child("resolutions")))
    m.resolutions.push_back(parse_resolution(r, doc.locate(n["resolutions"]) + ": resolutions"));
  if (m.resolutions.empty()) at.child("resolutions").fail(n["resolutions"], "needs at least one resolution");
  if (const YAML::Node scenes = n["scenes"]) {
    if (version < 2) at.child("scenes").fail(scenes, "scenes need manifest version 2");
    read_scenes(scenes, at.child("scenes"), m);
  } else {
    // A multi-scene set has the planes per scene (in the scenes' manifests).
    m.near_plane = config::Codec<double>::decode(need("near"), at.child("near"));
    m.far_plane = config::Codec<double>::decode(need("far"), at.child("far"));
    if (!(m.near_plane > 0) || !(m.far_plane > m.near_plane)) at.child("far").fail(n["far"], "need 0 < near < far");
  }
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
      if (f < 0 || f >= m.frames) sat.child(key).fail(split[key], "frame " + config::out_of_range(f, 0, m.frames - 1));
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
  if (const YAML::Node bsp = n["bsp_border"]) {
    const config::Cursor bat = at.child("bsp_border");
    if (!bsp.IsMap()) bat.fail(bsp, "expected a map {resolution, depth, samples, ...}, got " + config::detail::describe(bsp));
    for (const char* key : {"resolution", "depth", "samples"})
      if (!bsp[key]) bat.child(key).fail(bsp, std::string("missing required key '") + key + "'");
    const auto resolution = config::Codec<std::string>::decode(bsp["resolution"], bat.child("resolution"));
    if (resolution != m.resolutions.front().name())
      bat.child("resolution").fail(bsp["resolution"], "is " + resolution + ", but BSP border files are stored at the "
                                                      "smallest resolution, " + m.resolutions.front().name());
    m.bsp_border_depth = config::Codec<int>::decode(bsp["depth"], bat.child("depth"));
    config::detail::require_in_range(m.bsp_border_depth, 1, 4, bsp["depth"], bat.child("depth"));
    m.bsp_border_samples = config::Codec<int>::decode(bsp["samples"], bat.child("samples"));
    config::detail::require_in_range(m.bsp_border_samples, 2, 16, bsp["samples"], bat.child("samples"));
  }
  if (const YAML::Node jitter = n["jitter"]) read_jitter(jitter, at.child("jitter"), m);
  if (const YAML::Node samples = n["hr_samples"]) {
    m.hr_samples = config::Codec<int>::decode(samples, at.child("hr_samples"));
    if (hr_samples_per_side(m.hr_samples) == 0)
      at.child("hr_samples").fail(samples, "is " + std::to_string(m.hr_samples) + ", must be " + hr_samples_expected());
  }
  if (m.hr_samples > 1) {
    m.hr_filter = config::Codec<std::string>::decode(need("hr_filter"), at.child("hr_filter"));
    if (m.hr_filter != kHrFilterBox)
      at.child("hr_filter").fail(n["hr_filter"], "unknown filter '" + m.hr_filter + "' (known: " + kHrFilterBox + ")");
  } else if (n["hr_filter"]) {
    at.child("hr_filter").fail(n["hr_filter"], "a filter without hr_samples above 1 (one sample needs none)");
  }
  return m;
}

DatasetManifest scene_set_manifest(const std::string& name, const std::vector<Resolution>& resolutions,
                                   std::vector<ManifestScene> scenes, const std::vector<FrameSplit>& splits) {
  if (scenes.empty()) throw Error("scenes", "a multi-scene data set needs at least one scene");
  if (splits.size() != scenes.size()) throw Error("scenes", "one split per scene", ErrorKind::Internal);
  DatasetManifest m;
  m.name = name;
  m.resolutions = resolutions;
  std::string text;
  for (size_t i = 0; i < scenes.size(); ++i) {
    ManifestScene& sc = scenes[i];
    for (size_t j = 0; j < i; ++j)
      if (scenes[j].name == sc.name)
        throw Error("scenes", "two scenes are named '" + sc.name + "' (" + scenes[j].path + " and " + sc.path +
                                  "); scene names must be unique");
    sc.first_frame = m.frames;
    for (Split s : {Split::Train, Split::Val, Split::Test}) {
      auto& into = const_cast<std::vector<int>&>(m.split.of(s));
      for (int f : splits[i].of(s)) into.push_back(sc.first_frame + f);
    }
    if (sc.weight < 0)
      throw Error(sc.path, "scene '" + sc.name + "': weight " + config::out_of_range(sc.weight, 0, config::kUnbounded));
    if ((sc.weight > 0) != (scenes[0].weight > 0))
      throw Error(sc.path, "scene '" + sc.name + "': give every scene a weight, or none (then scenes are drawn in "
                           "proportion to their training frames)");
    m.frames += sc.frames;
    text += sc.name + "|" + sc.fingerprint + "|" + std::to_string(sc.frames) + "|";
  }
  for (const auto& r : resolutions) text += r.name() + "|";
  m.fingerprint = hex_fingerprint(text);
  m.scenes = std::move(scenes);
  return m;
}

fs::path scene_root(const fs::path& root, const ManifestScene& scene) {
  const fs::path p(scene.path);
  return p.is_absolute() ? p : root / p;
}

std::vector<ScenePart> scene_parts(const fs::path& root, const DatasetManifest& m) {
  if (m.scenes.empty()) return {ScenePart{m.name, root, m, 0, 0}};
  const std::string where = (root / "manifest.yaml").string();
  std::vector<ScenePart> parts;
  for (const auto& sc : m.scenes) {
    const fs::path dir = scene_root(root, sc);
    const std::string what = "scene '" + sc.name + "' (" + dir.string() + ")";
    if (!has_manifest(dir)) throw Error(where, what + ": no data set there (no manifest.yaml)");
    ScenePart part{sc.name, dir, read_manifest(dir), sc.first_frame, sc.weight};
    const DatasetManifest& s = part.manifest;
    if (!s.scenes.empty()) throw Error(where, what + ": is itself a multi-scene data set; list its scenes instead");
    if (!s.complete) throw Error(where, what + ": the render is incomplete (complete: false)");
    if (s.fingerprint != sc.fingerprint || s.frames != sc.frames)
      throw Error(where, what + ": changed since this set was written (fingerprint " + s.fingerprint + " and " +
                             std::to_string(s.frames) + " frames, recorded " + sc.fingerprint + " and " +
                             std::to_string(sc.frames) + "); write the set again (cgsr render / cgsr data merge)");
    if (s.resolutions != m.resolutions) {
      std::vector<std::string> have, want;
      for (const auto& r : s.resolutions) have.push_back(r.name());
      for (const auto& r : m.resolutions) want.push_back(r.name());
      throw Error(where, what + ": has resolutions " + join(have) + ", the set " + join(want));
    }
    parts.push_back(std::move(part));
  }
  return parts;
}

DatasetManifest merge_manifests(const fs::path& out, const std::string& name, const std::vector<fs::path>& data,
                                const std::vector<double>& weights) {
  if (data.empty()) throw Error("data", "give the data sets to merge");
  if (!weights.empty() && weights.size() != data.size())
    throw Error("weights", "give one weight per data set (" + std::to_string(data.size()) + "), got " +
                               std::to_string(weights.size()));
  const fs::path target = fs::weakly_canonical(fs::absolute(out));
  if (has_manifest(out) && read_manifest(out).scenes.empty())
    throw Error(out.string(), "holds a rendered data set; write the merged one into another directory");
  // Relative to the set where the two share a root, so the pair can be moved together.
  const auto reference = [&](const fs::path& dir) {
    const fs::path full = fs::weakly_canonical(fs::absolute(dir));
    const fs::path rel = full.lexically_relative(target);
    return rel.empty() ? full.string() : rel.string();
  };
  std::vector<ManifestScene> scenes;
  std::vector<FrameSplit> splits;
  std::vector<std::string> names;
  std::vector<Resolution> resolutions;
  for (size_t i = 0; i < data.size(); ++i) {
    const fs::path& dir = data[i];
    if (fs::weakly_canonical(fs::absolute(dir)) == target)
      throw Error(dir.string(), "is the output directory; write the merged data set into a directory of its own");
    const DatasetManifest m = read_manifest(dir);
    if (!m.complete) throw Error((dir / "manifest.yaml").string(), "the render is incomplete (complete: false)");
    if (i == 0) resolutions = m.resolutions;
    if (m.resolutions != resolutions) {
      std::vector<std::string> have, want;
      for (const auto& r : m.resolutions) have.push_back(r.name());
      for (const auto& r : resolutions) want.push_back(r.name());
      throw Error(dir.string(), "has resolutions " + join(have) + ", but " + data[0].string() + " has " + join(want) +
                                    ": merged data sets need the same resolutions (and so the same scales)");
    }
    if (!weights.empty() && !m.scenes.empty())
      throw Error(dir.string(), "is a multi-scene data set: weights are per single-scene data set (its scenes keep "
                                "none; merge its scenes' directories to weight them)");
    for (const ScenePart& part : scene_parts(dir, m)) {
      const double weight = weights.empty() ? 0 : weights[i];
      scenes.push_back({part.name, reference(part.root), part.manifest.fingerprint, 0, part.manifest.frames, weight});
      splits.push_back(part.manifest.split);
      names.push_back(part.name);
    }
  }
  DatasetManifest m = scene_set_manifest(name.empty() ? join(names, "+") : name, resolutions, scenes, splits);
  m.complete = true;
  return m;
}

}  // namespace cgsr
