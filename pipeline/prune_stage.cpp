#include "pipeline/prune_stage.h"

#include "core/yaml_json.h"
#include "models/model_file.h"
#include "render_data/dataset.h"

namespace cgsr::cli {

config::Schema<PruneCommandOptions> prune_command_schema() {
  config::Schema<PruneCommandOptions> s;
  s.field("model", &PruneCommandOptions::model, "trained model file to prune (e.g. the search result)").required();
  s.field("data", &PruneCommandOptions::data, "data set directory of the scene").required();
  add_prune_fields(s);
  s.field("resume", &PruneCommandOptions::resume, "continue the fine-tuning from the run directory's checkpoints");
  add_run_settings(s);
  return s;
}

void setup_prune(CLI::App& app) {
  add_command<PruneCommandOptions>(
      app, "prune", "Rendering-aware hybrid pruning: nested patterns, a per-frame choice from rendering information, static pruning",
      prune_command_schema,
      [](CLI::App& sub, std::vector<FlagAssignment>& flags) {
        flag_to_key(sub, flags, "--model", "model", "trained model file");
        flag_to_key(sub, flags, "--data", "data", "data set directory");
        flag_to_key(sub, flags, "--budget", "selector.budget",
                    "mean per-frame cost of the chosen patterns, as a fraction of the widest pattern's");
        flag_to_key(sub, flags, "--epochs", "finetune.epochs", "fine-tuning epochs");
        switch_to_key(sub, flags, "--resume", "resume", "continue an interrupted run in --out");
      },
      [](const PruneCommandOptions& options, const YAML::Node& resolved, RunDir* run_dir) {
        return run_prune(options, resolved, *run_dir);
      },
      /*always_run_dir=*/true);
}

nlohmann::ordered_json run_prune(const PruneCommandOptions& options, const YAML::Node& resolved, RunDir& run_dir) {
  // What the network and the dynamic pruning component's sampler read, nothing more.
  std::vector<RenderChannel> channels = read_model_file(options.model).spec.input_channels();
  for (auto c : options.sampler.render_channels()) channels.push_back(c);
  const Dataset data = open_for_channels(options.data, channels);
  return prune(options.model, data, options, run_dir.path(), options.resume, yaml_to_json(resolved));
}

}  // namespace cgsr::cli
