#pragma once
// The render job: what `cgsr render --config configs/scenes/NAME.yaml --out DIR` runs, and the
// render stage of `cgsr run` (and of its held-out scenes). Renders a scene at every requested
// resolution into the cgsr dataset format (render_data/render_job.h, DATASET_FORMAT.md).
// Re-running it on a partly rendered DIR resumes it.
//
// Several scenes into one data set: `cgsr render --scene a.yaml --scene b.yaml --out DIR`, or a
// scene-set config:
//   name: mixed
//   scenes:
//     - {config: configs/scenes/default.yaml}
//     - {config: configs/scenes/arena.yaml, weight: 2, frames: 60}   # name, weight, frames optional
//     - {config: configs/scenes/variety.yaml, name: variety_3, set: [scene.variant=3]}   # overrides
// Each entry is a scene config as above, rendered as it says (with the command's seed) into
// DIR/scenes/<name>; DIR/manifest.yaml lists the scenes (dataset_manifest.h).

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/run_dir.h"
#include "pipeline/run_settings.h"
#include "render_data/render_job.h"

namespace cgsr {

// A scene of a scene set.
struct SceneSetEntry {
  std::string config;  // a scene's render config (configs/scenes/*.yaml)
  std::string name;    // empty: the config's name, else the file's stem
  double weight = 0;   // sampling weight; 0 for every entry: proportional to training frames
  int frames = 0;      // 0: the config's
  std::vector<std::string> set;  // "key.path=value" overrides of the config, as --set (e.g. scene.variant=3)
};

struct RenderOptions : RunSettings, RenderJobOptions {
  std::vector<SceneSetEntry> scenes;  // a scene set instead of `scene`
};

config::Schema<RenderOptions> render_schema();
// The scene set's entries as render jobs, each parsed from its config file with its overrides.
std::vector<SceneRenderJob> scene_set_jobs(const RenderOptions& options);
// Renders into `out` and marks the data set complete: for a caller that writes nothing more there.
nlohmann::ordered_json run_render(const RenderOptions& options, const std::filesystem::path& out);
// Renders into a run directory (`cgsr render`, the render stage of `cgsr run`), whose manifest is
// marked complete only once its results.json is written: a data set never looks finished before
// its run directory is.
nlohmann::ordered_json run_render(const RenderOptions& options, RunDir& run_dir);
// What `cgsr render --check` does beyond the schema: the checks the run makes before its first
// frame (resolutions, and each scene built from its block, which parses the source's options),
// so a config --check passes is not rejected by the run. Returns a line per scene.
std::string check_render(const RenderOptions& options);

}  // namespace cgsr
