#pragma once
// Datasets of aligned multi-resolution frames, whatever their layout on disk:
//
//   Dataset data = Dataset::open("runs/render-default");       // layout detected
//   const Frame& hr = *data.frame(12, data.resolution_index({640, 480}));
//   data.frames(Split::Train)                                  // frame indices of a split
//
// Layouts (the "dataset loader" registry, one entry per layout):
//   cgsr          our own format, written by `cgsr render` (a directory with manifest.yaml)
//   cgsr-release  the CGSR data release: <trace>/<width>/frame###.sim.ppm + feature###.bmp
//                 (R edge mask 0/255, G normalized depth, B normal angle)
//   glob          any capture described by a YAML file of per-channel glob patterns (glob_layout.h)
// Every loader produces the same in-memory Frame (frame.h). Channels the data lacks are derived
// on request (derive_channels.h) and listed in info().derived. Frames are cached up to a byte
// budget (least recently used frames are dropped) while the machine keeps a reserve of memory
// available; the cache is thread-safe.

#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/registry.h"
#include "render_data/dataset_manifest.h"
#include "render_data/edges.h"
#include "render_data/frame.h"
#include "render_data/hr_samples.h"

namespace cgsr {

// Half the machine's physical memory, in GiB: the frame cache's default budget. A cache that
// overflows decodes the same frames again and again (training on configs/general.yaml's
// OpenArena set reads 1300 frames with HR G-buffers, 8 GB), and the processes that read a data
// set need little else; the cache changes no result, only how often a frame is decoded.
double default_frame_cache_gb();

// An eighth of the machine's physical memory, in GiB: what a frame cache leaves available. A
// cache stops growing when the machine has less than this available, so that processes reading
// data sets side by side (a run beside an evaluation) cannot take more than the machine has.
double default_frame_cache_reserve_gb();

struct DatasetOpenOptions {
  std::string layout = "auto";           // auto, or a registered layout name
  std::vector<std::string> channels;     // channels to load; empty: every stored + derived channel
  std::vector<std::string> derive;       // channels to derive when the data lacks them
  bool clean_grid_lines = false;         // cgsr-release: remove the simulator's tile-grid lines
  double near_plane = 0, far_plane = 0;  // layouts without planes (cgsr-release, glob): 0 = layout default
  double vfov = 0;                       // vertical FOV for derived normals; 0 = layout default
  double cache_gb = default_frame_cache_gb();  // frame cache budget, GiB
  double cache_reserve_gb = default_frame_cache_reserve_gb();  // memory the cache leaves available, GiB
  EdgeSettings edges;                    // thresholds for derived edges
};

config::Schema<DatasetOpenOptions> dataset_open_schema();

// A scene of a data set: a run of consecutive frames rendered from one scene and camera path.
// Every data set has at least one; a multi-scene cgsr data set (dataset_manifest.h) has several.
struct SceneInfo {
  std::string name;
  int first_frame = 0, frames = 0;
  double near_plane = 0.05, far_plane = 500, vfov = 60;  // the depth planes and FOV of its frames
  double weight = 0;  // sampling weight; 0 for every scene: proportional to its training frames
  // Its ground truth (DatasetInfo::hr_samples, target): what a one-scene view of a set names.
  int hr_samples = 0;
  std::string target = kCapturedTarget;
  bool contains(int frame) const { return frame >= first_frame && frame < first_frame + frames; }
};

struct DatasetInfo {
  std::string name, layout;
  std::filesystem::path root;
  int frames = 0;
  std::vector<Resolution> resolutions;  // ascending
  double near_plane = 0.05, far_plane = 500, vfov = 60;
  std::vector<RenderChannel> stored;    // read from files (at one resolution at least)
  std::vector<RenderChannel> derived;   // computed on load
  std::vector<RenderChannel> channels;  // what frames carry: loaded stored + derived, fixed order
  // Per resolution: what the files hold (loaders fill it; empty = `stored` everywhere), and what
  // its frames carry after loading and derivation (a capture may have depth only at LR).
  std::vector<std::vector<RenderChannel>> stored_at, channels_at;
  FrameSplit split;
  // In frame order, covering the frames (of a one-scene view: that scene's frames). Loaders
  // without scenes leave it empty and get one scene of every frame named after the data set.
  std::vector<SceneInfo> scenes;
  std::vector<std::string> notes;       // e.g. "tile-grid lines removed from edges"
  // Every frame has a sub-pixel BSP border image at resolutions[0] (Frame::bsp_border; cgsr data
  // sets rendered with bsp_border).
  bool bsp_border = false;
  // What the frames above the smallest resolution show, the ground truth the reports name: a cgsr
  // render's hr_samples (hr_samples.h; 0 for anything else) and its description, e.g.
  // "supersampled (4 samples per pixel, box filter)"; captures are taken as they come.
  int hr_samples = 0;
  std::string target = kCapturedTarget;
};

// What a layout implements: metadata, and one frame at one resolution with the given channels
// (a subset of info().stored). Errors name the file and frame.
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual const DatasetInfo& info() const = 0;
  virtual Frame load(int frame, size_t resolution, const std::vector<RenderChannel>& channels) const = 0;
};

struct DatasetLoader {
  std::function<bool(const std::filesystem::path&)> detect;  // does `path` look like this layout?
  std::function<std::unique_ptr<FrameSource>(const std::filesystem::path&, const DatasetOpenOptions&)> open;
};

Registry<DatasetLoader>& dataset_loaders();  // cgsr, cgsr-release, glob already in it

class Dataset {
 public:
  // `path`: a dataset directory, or a glob-layout YAML file. Throws cgsr::Error naming the path
  // when no layout matches, listing the layouts.
  static Dataset open(const std::filesystem::path& path, const DatasetOpenOptions& options = {});

  const DatasetInfo& info() const;
  int frame_count() const;
  const std::vector<Resolution>& resolutions() const;
  size_t resolution_index(const Resolution& r) const;  // cgsr::Error listing the resolutions
  std::vector<int> frames(Split split) const;           // Split::All: 0 .. N-1 (a view: its scene's)

  const std::vector<SceneInfo>& scenes() const;
  const SceneInfo& scene_of(int frame) const;           // cgsr::Error when out of range
  // Whether `frame` has a predecessor in its own scene (the previous frame of a sequence: motion
  // vectors, temporal error and stateful upscalers read it; a scene's first frame has none).
  bool has_previous(int frame) const;
  // A view of one scene (by name; cgsr::Error listing the names): frame indices stay the set's,
  // frames() and the split hold that scene's only; frames are shared with this data set's cache.
  Dataset scene(const std::string& name) const;

  // Cached; safe to call from several threads.
  std::shared_ptr<const Frame> frame(int index, size_t resolution) const;
  // Bypasses the cache (data check, benchmarks).
  Frame load(int index, size_t resolution) const;

  size_t cached_bytes() const;

 private:
  struct Impl;
  std::shared_ptr<Impl> impl_;
  std::shared_ptr<const DatasetInfo> view_;  // a one-scene view's info; null: the whole set
};

// At most `count` frames spread evenly over `frames`, in order (count <= 0: all of them).
std::vector<int> spread_frames(const std::vector<int>& frames, int count);

// The data set at `path` loading only `channels` of its rendering information (those it has) and
// the edge map (the smallest channel; an empty list would mean all): decoding the other G-buffers,
// motion above all, costs more than the work on a frame, and on a large set a frame cache full of
// them overflows and decodes frames over and over.
Dataset open_for_channels(const std::filesystem::path& path, const std::vector<RenderChannel>& channels);

// The data set at `path` with every channel it gives by default, plus those of `channels` that are
// derived only when asked for (history, jitter): for readers that pick their channels later (`cgsr ablate`'s
// channel sets). Data that cannot give them is the error opening them names.
Dataset open_with_asked_channels(const std::filesystem::path& path, const std::vector<RenderChannel>& channels);

// Loader entry points (dataset.cpp registers them).
std::unique_ptr<FrameSource> open_cgsr_dataset(const std::filesystem::path& root, const DatasetOpenOptions& options);
std::unique_ptr<FrameSource> open_cgsr_release(const std::filesystem::path& root, const DatasetOpenOptions& options);
bool looks_like_cgsr_release(const std::filesystem::path& root);
std::unique_ptr<FrameSource> open_glob_layout(const std::filesystem::path& path, const DatasetOpenOptions& options);
bool looks_like_glob_layout(const std::filesystem::path& path);

// The channels that `options.channels` names (empty: all stored ones plus `derive`), checked
// against what the data has and what can be derived; fills derived, channels and channels_at.
// The bsp channel (render_channels.h) is derived on load when asked for (and by default when the
// data set has BSP border files); asked for without them it is an error naming the data set and
// how to render them.
// The history channel (render_channels.h, history_channel.h) is derived only when asked for by
// name (it reads kHistoryFrames more frames per frame); asked for on data that cannot give it at
// any resolution it is an error naming the data set, each resolution and what it lacks. The
// jitter channel is derived only when asked for by name, from each LR frame's jitter, on any data.
void resolve_channels(DatasetInfo& info, const DatasetOpenOptions& options);
// info.derived without bsp, history and jitter: the channels derive_channels computes from depth.
std::vector<RenderChannel> depth_derived(const DatasetInfo& info);
// s when `resolution` is s times resolutions[0] in both axes (s >= 1), else 0.
int lr_multiple(const DatasetInfo& info, size_t resolution);
// Whether `resolution` is an integer multiple of the BSP resolution (resolutions[0]) of a data set
// with BSP border files: where the bsp channel exists.
bool bsp_available_at(const DatasetInfo& info, size_t resolution);
// Why the history channel cannot be made at `resolution` ("" when it can): not an integer
// multiple of resolutions[0], or no motion / depth stored there (or no depth at resolutions[0]).
std::string history_missing_at(const DatasetInfo& info, size_t resolution);
bool history_available_at(const DatasetInfo& info, size_t resolution);
// Whether `frame` has a predecessor in its own scene (Dataset::has_previous).
bool has_previous_frame(const DatasetInfo& info, int frame);
const std::vector<RenderChannel>& channels_at(const DatasetInfo& info, size_t resolution);

}  // namespace cgsr
