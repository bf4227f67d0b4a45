#pragma once
// The cgsr dataset format: one directory per rendered sequence, one folder per resolution and
// channel, one file per frame, and manifest.yaml describing it all (DATASET_FORMAT.md).
//
//   DIR/manifest.yaml
//   DIR/<W>x<H>/<file kind>/<frame:06d>.<ext>     e.g. DIR/320x240/depth/000012.exr

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

struct DatasetManifest {
  static constexpr const char* kFormat = "cgsr-dataset";
  static constexpr int kVersion = 1;
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

  std::filesystem::path file(const std::filesystem::path& root, int frame, size_t resolution, FileKind kind) const;
};

std::filesystem::path frame_file(const std::filesystem::path& root, const Resolution& resolution, FileKind kind,
                                 int frame);

void write_manifest(const std::filesystem::path& root, const DatasetManifest& manifest);  // atomic
// Throws cgsr::Error naming manifest.yaml and the key when it is missing or malformed.
DatasetManifest read_manifest(const std::filesystem::path& root);
bool has_manifest(const std::filesystem::path& root);

}  // namespace cgsr
