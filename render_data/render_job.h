#pragma once
// `cgsr render` as a library call: build a scene from its source block, render every frame at
// every resolution, write the dataset (frame_files.h) and its manifest. A killed render resumes:
// frames whose files all exist are skipped, and the manifest's fingerprint makes sure the
// directory holds a render of the same configuration.
//
// Render config (configs/scenes/*.yaml):
//   name: default
//   frames: 90
//   resolutions: [320x240, 640x480]     # every one an integer multiple of the smallest
//   shadows: true
//   shadow_map_size: 1024
//   edges: {depth_threshold: 0.08, crease_angle: 40, id_changes: true}
//   bsp_border: {depth: 2, samples: 4}  # sub-pixel BSP border files at the smallest resolution
//                                       # (bsp_border.h); depth 0 (the default): none
//   jitter: {sequence: halton, phases: 8}  # sub-pixel jitter of the smallest resolution's frames
//                                       # (jitter.h); sequence none (the default): none
//   hr_samples: 4                       # samples per pixel of the colour of every resolution but
//                                       # the smallest (the targets): n x n on a grid, n 1..4, box
//                                       # filter in linear light (hr_samples.h); 1 (the default):
//                                       # one, aliased. G-buffers keep one sample per pixel
//   scene: {type: procedural, ...}      # scene_source.h

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "core/config.h"
#include "render_data/bsp_border_builder.h"
#include "render_data/dataset_manifest.h"
#include "render_data/edges.h"
#include "render_data/hr_samples.h"
#include "render_data/jitter.h"

namespace cgsr {

struct RenderJobOptions {
  std::string name;  // dataset name; empty: the scene's name
  int frames = 90;
  std::vector<std::string> resolutions = {"320x240", "640x480"};
  bool shadows = true;
  int shadow_map_size = 1024;
  EdgeSettings edges;
  BspBorderSettings bsp_border;
  JitterSettings jitter;
  int hr_samples = 1;  // samples per pixel of the targets' colour, n x n (hr_samples.h)
  config::Block scene;
};

config::Schema<EdgeSettings> edge_settings_schema();
config::Schema<BspBorderSettings> bsp_border_settings_schema();

// Adds the render-job keys to a command schema whose options struct derives from RenderJobOptions.
// `scene_required` false: the caller checks `scene` (e.g. against a scene set).
template <class T>
void add_render_job_fields(config::Schema<T>& s, bool scene_required = true) {
  s.field("name", static_cast<std::string T::*>(&RenderJobOptions::name), "dataset name (default: the scene's name)");
  s.field("frames", static_cast<int T::*>(&RenderJobOptions::frames), "frames to render").range(1, 1000000);
  s.field("resolutions", static_cast<std::vector<std::string> T::*>(&RenderJobOptions::resolutions),
          "resolutions WxH, each an integer multiple of the smallest")
      .check([](const std::vector<std::string>& v) { return !v.empty(); }, "needs at least one resolution");
  s.field("shadows", static_cast<bool T::*>(&RenderJobOptions::shadows), "render shadow maps for lights that cast shadows");
  s.field("shadow_map_size", static_cast<int T::*>(&RenderJobOptions::shadow_map_size), "shadow map texels per side")
      .range(16, 8192);
  s.section("edges", static_cast<EdgeSettings T::*>(&RenderJobOptions::edges), edge_settings_schema(),
            "edge detection thresholds");
  s.section("bsp_border", static_cast<BspBorderSettings T::*>(&RenderJobOptions::bsp_border), bsp_border_settings_schema(),
            "sub-pixel BSP border files at the smallest resolution (depth 0: none)");
  // Off, the resolved config (and so `cgsr run`'s render stage hash) is what it was before the key.
  s.omit_when("bsp_border", [](const T& o) { return !o.bsp_border.enabled(); });
  s.section("jitter", static_cast<JitterSettings T::*>(&RenderJobOptions::jitter), jitter_settings_schema(),
            "sub-pixel jitter of the smallest resolution's frames (sequence none: none)");
  // Off, the resolved config (and the render stage hash) is what it was before the key.
  s.omit_when("jitter", [](const T& o) { return !o.jitter.enabled(); });
  s.field("hr_samples", static_cast<int T::*>(&RenderJobOptions::hr_samples),
          "samples per pixel of the colour of every resolution but the smallest (n x n, box filter in linear light)")
      .check([](int v) { return hr_samples_per_side(v) > 0; }, "must be " + hr_samples_expected());
  // At 1, the resolved config (and the render stage hash) is what it was before the key.
  s.omit_when("hr_samples", [](const T& o) { return o.hr_samples == 1; });
  s.block("scene", static_cast<config::Block T::*>(&RenderJobOptions::scene), "scene source {type: procedural, ...}");
  if (scene_required)
    s.validate([](const T& o, const config::Cursor& at, const YAML::Node& node) {
      if (!o.scene.node || o.scene.node.IsNull()) at.child("scene").fail(node, "missing required key 'scene'");
    });
}

// Parses and checks the resolutions: sorted ascending; each must be an integer multiple (same
// aspect) of the smallest, else a cgsr::Error naming the pair.
std::vector<Resolution> parse_resolutions(const std::vector<std::string>& texts, const std::string& context);

struct RenderJobResult {
  DatasetManifest manifest;
  int rendered = 0, skipped = 0;  // frames rendered now, frames found complete (resumed)
  double seconds = 0;
  size_t triangles = 0;
  // Mean bytes per frame, per resolution and per file kind (all_file_kinds() order).
  std::vector<std::vector<double>> bytes_per_kind;
  // With BSP border files: their mean bytes per frame, the share of the smallest resolution's
  // pixels that have a tree, and lines per tree (means over the frames).
  double bsp_border_bytes = 0, bsp_border_fraction = 0, bsp_border_lines = 0;
  // Per resolution: the pixels whose motion was rejected (GBuffer::motion_rejected: their point
  // was behind the previous camera's near plane), over the frames rendered now (a resumed frame's
  // count is not stored), the most in one frame and the frames with any; and the pixels whose
  // motion was cut at the guard band (GBuffer::motion_clamped).
  struct MotionRejected {
    int64_t pixels = 0, max_per_frame = 0, clamped = 0;
    int frames = 0;
  };
  std::vector<MotionRejected> motion_rejected;
};

// Renders into `out` (created if needed). `progress` is called after each frame (done, total).
// The manifest stays `complete: false`: the caller writes whatever else belongs in `out`, then
// calls finish_render, so a data set never looks complete before all of it is written.
RenderJobResult run_render_job(const RenderJobOptions& options, uint64_t seed, const std::filesystem::path& out,
                               const std::function<void(int, int)>& progress = {});

// The fingerprint a render of `options` with `seed` records (its resume guard).
std::string render_fingerprint(const RenderJobOptions& options, uint64_t seed);

// One scene of a multi-scene render.
struct SceneRenderJob {
  RenderJobOptions options;  // options.name: the scene's name, also its directory (scenes/<name>)
  double weight = 0;         // sampling weight (0 for every scene: proportional to training frames)
  std::string origin;        // where the scene was configured (its config file), for errors
};

struct SceneSetRenderResult {
  DatasetManifest manifest;           // the set's (dataset_manifest.h)
  std::vector<RenderJobResult> scenes;
  int rendered = 0, skipped = 0;
  double seconds = 0;
};

// Renders every scene into `out`/scenes/<name> (each a single-scene data set that resumes as
// run_render_job does, marked complete when its frames are; every scene with `seed`) and writes
// the set's manifest into `out`, `complete: false` until finish_render. The scenes need the
// same resolutions; a directory holding a set of other scenes or configurations is an error.
// `progress` counts the frames of all scenes. `name` empty: the scene names joined by '+'.
SceneSetRenderResult run_scene_set_render(const std::string& name, const std::vector<SceneRenderJob>& jobs,
                                          uint64_t seed, const std::filesystem::path& out,
                                          const std::function<void(int, int)>& progress = {});

// The last step of a render: `manifest` (a result's) written into `out` as complete.
void finish_render(const std::filesystem::path& out, DatasetManifest manifest);

// "1.2 MB", "340 KB": for size reports.
std::string human_bytes(double bytes);

}  // namespace cgsr
