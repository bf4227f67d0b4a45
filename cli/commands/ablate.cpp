#include "cli/commands/ablate.h"

#include <spdlog/spdlog.h>

#include <cstdio>

#include "core/atomic_file.h"
#include "models/model_file.h"
#include "render_data/dataset.h"

namespace cgsr::cli {

config::Schema<AblateOptions> ablate_schema() {
  config::Schema<AblateOptions> s;
  s.field("data", &AblateOptions::data, "data set directory").required();
  s.field("model", &AblateOptions::model, "the trained plain network (model file)").required();
  s.section("ablation", &AblateOptions::ablation, ablation_schema_fields(), "variants, seeds, schedule, evaluation");
  add_run_settings(s);
  return s;
}

void setup_ablate(CLI::App& app) {
  add_command<AblateOptions>(
      app, "ablate",
      "Ablate rendering information: the plain network trained on against every RIT source, channels left out "
      "and a small network, over seeds",
      ablate_schema,
      [](CLI::App& sub, std::vector<FlagAssignment>& flags) {
        flag_to_key(sub, flags, "--data", "data", "data set directory");
        flag_to_key(sub, flags, "--model", "model", "the trained plain network (model file)");
        flag_to_key(sub, flags, "--steps", "ablation.schedule.steps", "optimizer steps of every variant");
      },
      [](const AblateOptions& options, const YAML::Node&, RunDir* run_dir) { return run_ablate(options, *run_dir); },
      /*always_run_dir=*/true);
}

nlohmann::ordered_json run_ablate(const AblateOptions& options, RunDir& run_dir) {
  std::vector<RenderChannel> channels = parse_channels(options.ablation.rit.channels);
  for (const auto& set : options.ablation.channel_sets)
    for (auto c : parse_channels(set)) channels.push_back(c);
  const Dataset data = open_with_asked_channels(options.data, channels);
  const Model parent = load_model(options.model);
  const AblationResult result = run_ablation(*parent.network, data, options.ablation, run_dir.path());
  const std::string markdown = ablation_markdown(result);
  write_file_atomic(run_dir.file("ablation.md"), markdown);
  write_file_atomic(run_dir.file("ablation.csv"), ablation_csv(result));
  if (result.rows.size() > 1) write_ablation_chart(run_dir.file("ablation.png"), result);
  std::printf("%s\n", markdown.c_str());
  return to_json(result);
}

}  // namespace cgsr::cli
