#pragma once
// Held-out evaluation for `cgsr run`: scenes the networks never saw in training, rendered at the
// training data's LR and HR sizes and evaluated with every model of the run and the classic
// baselines. In its own scene a network can beat bicubic by a dB and still lose to it on another
// level; this is the part of the report that says so.
//
//   heldout:
//     scenes: [configs/scenes/corridors.yaml]   # cgsr render configs; their resolutions are replaced
//     frames: 8                                  # frames rendered and evaluated per scene

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/config.h"
#include "eval/evaluation.h"
#include "pipeline/render_stage.h"
#include "render_data/dataset.h"

namespace cgsr {

struct HeldoutOptions {
  std::vector<std::string> scenes;  // cgsr render configs of scenes not in the training data
  int frames = 8;                   // frames rendered per scene, all evaluated
};
config::Schema<HeldoutOptions> heldout_schema();

struct HeldoutJob {
  std::vector<std::string> models;  // cgsr eval entries: classic upscaler names, model files
  int scale = 2;
  Resolution lr;                    // the training data's LR size; HR is lr * scale
  std::string training_scene;       // the training data set's name, which no held-out scene may take
  EvalOptions eval;                 // metric options of the run (split, frames and latency are replaced)
  int seed = 0, threads = 0;
};

// A held-out scene's render config (one scene: a scene set is an error naming the file).
RenderOptions heldout_scene(const std::string& config);

// Renders each scene into dir/<n>_<scene>/data (resuming an interrupted render) and evaluates the
// job's models on all its frames into dir/<n>_<scene>/eval. Returns {"scenes": [{scene, data,
// results}]}, results being the eval's results.json.
nlohmann::ordered_json run_heldout(const HeldoutOptions& options, const HeldoutJob& job,
                                   const std::filesystem::path& dir);

// The eval results.json files and the scene (data set) names of a run_heldout() summary, in
// scene order; none for an empty summary (no held-out scenes).
std::vector<std::string> heldout_result_files(const nlohmann::ordered_json& summary);
std::vector<std::string> heldout_scenes(const nlohmann::ordered_json& summary);

}  // namespace cgsr
