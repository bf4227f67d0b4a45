#pragma once
// The cgsr dataset format: one directory per rendered sequence, one folder per resolution and
// channel, one file per frame, and manifest.yaml describing it all (DATASET_FORMAT.md).
//
//   DIR/manifest.yaml
//   DIR/<W>x<H>/<file kind>/<frame:06d>.<ext>     e.g. DIR/320x240/depth/000012.exr
//
// A multi-scene data set (format version 2) is a manifest.yaml listing its scenes, each a
// complete single-scene data set in a directory of its own (`cgsr render` with several scenes
// writes them to DIR/scenes/<name>; `cgsr data merge` refers to existing ones without copying).
// Its frames are the scenes' frames one scene after the other, and its split is the union of the
// scenes' own splits, so every scene contributes to train, val and test. A manifest without
// scenes (version 1, still written for a single scene) is one scene.

#include <array>
#include <filesystem>
#include <string>
#include <vector>

namespace cgsr {

struct Resolution {
  int width = 0, height = 0;
  std::string name() const { return std::to_string(width) + "x" + std::to_string(height); }
  bool operator==(const Resolution& o) const { return width == o.width && height == o.height; }
  bool operator!=(const Resolution& o) const { return !(*this == o); }
};
Resolution parse_resolution(const std::string& text, const std::string& context);  // "320x240"

// The files stored per frame and resolution, and how each is encoded.
enum class FileKind { Color, Depth, Normal, NormalAngle, Edge, Id, Motion };
const std::vector<FileKind>& all_file_kinds();
const std::string& file_kind_name(FileKind kind);  // folder name: color, depth, normal, ...
const std::string& file_kind_extension(FileKind kind);  // ".png" or ".exr"
const std::string& file_kind_encoding(FileKind kind);   // human-readable, recorded in the manifest

enum class Split { Train, Val, Test, All };
const std::string& split_name(Split split);
Split split_from_name(const std::string& name);  // train, val, test, all

struct FrameSplit {
  std::vector<int> train, val, test;
  const std::vector<int>& of(Split split) const;  // not for Split::All
};

// The paper's split: 10% of the frames for test, sampled uniformly over the sequence (frame
// round((k + 0.5) * N / n_test) for k < n_test), then 20% for validation spread uniformly over
// the remaining frames, the rest (70%) for training. Deterministic; sequences shorter than 3
// frames are all training frames.
FrameSplit make_split(int frames, double test_fraction = 0.1, double val_fraction = 0.2);

// One scene of a multi-scene data set: frames first_frame .. first_frame + frames - 1 of the set
// are frames 0 .. frames - 1 of the single-scene data set in `path`.
struct ManifestScene {
  std::string name;         // unique within the set
  std::string path;         // relative to the set's directory, or absolute
  std::string fingerprint;  // the scene data set's fingerprint when the set was written
  int first_frame = 0, frames = 0;
  double weight = 0;        // sampling weight; 0 for every scene: proportional to training frames
};

struct DatasetManifest {
  static constexpr const char* kFormat = "cgsr-dataset";
  static constexpr int kVersion = 2;             // adds `scenes`
  static constexpr int kSingleSceneVersion = 1;  // what a manifest without scenes is written as
  std::string name;
  bool complete = false;     // false while `cgsr render` is still writing frames
  std::string fingerprint;   // hash of everything that determines the frames (resume guard)
  int frames = 0;
  std::vector<Resolution> resolutions;  // ascending
  double near_plane = 0.05, far_plane = 500;
  double vfov = 60;          // vertical field of view at frame 0, degrees (informative)
  std::string scene_source;  // e.g. "procedural"
  uint64_t seed = 0;
  FrameSplit split;
  std::vector<double> bytes_per_frame;  // per resolution, mean over the frames (complete datasets)
  // Sub-pixel BSP border files (render_data/bsp_border_file.h) of every frame at the smallest
  // resolution, with the depth and samples per pixel side they were built with; depth 0: none
  // (and no `bsp_border` key, so manifests without them are written as before).
  int bsp_border_depth = 0, bsp_border_samples = 0;
  // Sub-pixel jitter of the smallest resolution's frames (render_data/jitter.h): the sequence
  // ("halton"), its phases and every frame's offset in pixels of that resolution, {x, y} each in
  // [-0.5, 0.5). Empty sequence: not jittered (and no `jitter` key, so manifests without it are
  // written as before and older ones load as unjittered).
  std::string jitter_sequence;
  int jitter_phases = 0;
  std::vector<std::array<double, 2>> jitter_offsets;  // per frame
  // Samples per pixel of the colour of every resolution but the smallest (render_data/hr_samples.h)
  // and the filter that resolved them; 1 (no `hr_samples` key, as before the option): aliased.
  int hr_samples = 1;
  std::string hr_filter;  // "box" when hr_samples > 1
  // Multi-scene data sets only (then the frames live in the scenes' directories, and the planes,
  // field of view, seed and sizes are each scene's own).
  std::vector<ManifestScene> scenes;

  std::filesystem::path file(const std::filesystem::path& root, int frame, size_t resolution, FileKind kind) const;
};

std::filesystem::path frame_file(const std::filesystem::path& root, const Resolution& resolution, FileKind kind,
                                 int frame);

// 16 hex digits of a 64-bit FNV-1a hash of `text`: the manifests' fingerprints.
std::string hex_fingerprint(const std::string& text);

void write_manifest(const std::filesystem::path& root, const DatasetManifest& manifest);  // atomic
// Throws cgsr::Error naming manifest.yaml and the key when it is missing or malformed.
DatasetManifest read_manifest(const std::filesystem::path& root);
bool has_manifest(const std::filesystem::path& root);

// A multi-scene manifest from its scenes (first_frame is filled in) and each scene's split in
// its own frame numbers: frames, split (the union, shifted) and fingerprint (of the scenes' names,
// fingerprints and frame counts; weights do not change frames, so they are not in it).
DatasetManifest scene_set_manifest(const std::string& name, const std::vector<Resolution>& resolutions,
                                   std::vector<ManifestScene> scenes, const std::vector<FrameSplit>& splits);

// A single-scene data set that holds frames of a data set: the whole of a single-scene one, or
// one scene of a multi-scene one.
struct ScenePart {
  std::string name;
  std::filesystem::path root;  // the scene data set's directory
  DatasetManifest manifest;    // its own (single-scene) manifest
  int first_frame = 0;         // its frame 0 in the set's numbering
  double weight = 0;
};
// The scene data sets of the data set in `root` (whose manifest is `manifest`), checked against
// what the manifest recorded: each exists, is complete, has the set's resolutions and the
// recorded fingerprint and frame count. Errors name the set's manifest.yaml and the scene.
std::vector<ScenePart> scene_parts(const std::filesystem::path& root, const DatasetManifest& manifest);
// `cgsr data merge`: a multi-scene manifest in `out` referring to the scenes of existing data sets
// (paths relative to `out` where possible; nothing is copied). A multi-scene data set contributes
// each of its scenes. `weights`: none, or one per data set (single-scene ones only). The data sets
// must be complete and have the same resolutions, else a cgsr::Error naming both. `name` empty:
// the scene names joined by '+'. Writes nothing; write_manifest(out, result) does.
DatasetManifest merge_manifests(const std::filesystem::path& out, const std::string& name,
                                const std::vector<std::filesystem::path>& data, const std::vector<double>& weights);

// `path` of a scene entry, resolved against the set's directory.
std::filesystem::path scene_root(const std::filesystem::path& root, const ManifestScene& scene);

}  // namespace cgsr
