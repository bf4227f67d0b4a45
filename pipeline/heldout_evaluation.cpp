#include "pipeline/heldout_evaluation.h"

#include <spdlog/spdlog.h>

#include <set>

#include "core/error.h"
#include "pipeline/eval_stage.h"
#include "pipeline/render_stage.h"

namespace cgsr {
namespace fs = std::filesystem;

config::Schema<HeldoutOptions> heldout_schema() {
  config::Schema<HeldoutOptions> s;
  s.field("scenes", &HeldoutOptions::scenes,
          "cgsr render configs of scenes not in the training data (rendered at the training data's LR and HR sizes)");
  s.field("frames", &HeldoutOptions::frames, "frames rendered and evaluated per held-out scene").range(1, 10000);
  return s;
}

RenderOptions heldout_scene(const std::string& config) {
  RenderOptions scene = config::parse_document(config::Document::load_file(config), render_schema());
  if (!scene.scenes.empty()) throw Error(config, "is a scene set; list its scene configs under heldout.scenes one by one");
  return scene;
}

nlohmann::ordered_json run_heldout(const HeldoutOptions& options, const HeldoutJob& job, const fs::path& dir) {
  nlohmann::ordered_json summary;
  summary["scenes"] = nlohmann::ordered_json::array();
  std::set<std::string> names;
  for (size_t i = 0; i < options.scenes.size(); ++i) {
    RenderOptions scene = heldout_scene(options.scenes[i]);
    scene.seed = job.seed;
    scene.threads = job.threads;
    scene.frames = options.frames;
    scene.resolutions = {job.lr.name(), Resolution{job.lr.width * job.scale, job.lr.height * job.scale}.name()};
    const fs::path where = dir / (std::to_string(i + 1) + "_" + fs::path(options.scenes[i]).stem().string());
    spdlog::info("held-out scene {}/{}: {}", i + 1, options.scenes.size(), options.scenes[i]);
    const auto rendered = run_render(scene, where / "data");
    const std::string name = rendered.at("name").get<std::string>();
    // The report and the verdict tell scenes apart by data set name.
    if (name == job.training_scene)
      throw Error(options.scenes[i], "the held-out scene is named '" + name +
                                         "', as the training data is; give it another name (key 'name')");
    if (!names.insert(name).second)
      throw Error(options.scenes[i], "a second held-out scene named '" + name + "'; give it another name (key 'name')");

    EvalCommandOptions evaluation;
    evaluation.seed = job.seed;
    evaluation.threads = job.threads;
    evaluation.data = (where / "data").string();
    evaluation.scale = job.scale;
    evaluation.models = job.models;
    evaluation.eval = job.eval;
    evaluation.eval.split = "all";
    evaluation.eval.frames.clear();
    evaluation.eval.max_frames = 0;
    evaluation.eval.latency_runs = 0;  // quality only: the report times every model on the run's test frames
    RunDir eval_dir(where / "eval", /*own_log=*/false);
    eval_dir.write_config(eval_schema().emit(evaluation));
    const auto results = run_eval(evaluation, &eval_dir);
    eval_dir.write_results(results);
    summary["scenes"].push_back({{"scene", name},
                                 {"config", options.scenes[i]},
                                 {"data", evaluation.data},
                                 {"results", (where / "eval" / "results.json").string()}});
  }
  return summary;
}

namespace {
std::vector<std::string> scene_entries(const nlohmann::ordered_json& summary, const char* key) {
  std::vector<std::string> out;
  if (!summary.is_object() || !summary.contains("scenes")) return out;
  for (const auto& s : summary.at("scenes")) out.push_back(s.at(key).get<std::string>());
  return out;
}
}  // namespace

std::vector<std::string> heldout_result_files(const nlohmann::ordered_json& summary) {
  return scene_entries(summary, "results");
}

std::vector<std::string> heldout_scenes(const nlohmann::ordered_json& summary) {
  return scene_entries(summary, "scene");
}

}  // namespace cgsr
