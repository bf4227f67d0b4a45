#include "pipeline/prune_stage.h"

#include "core/yaml_json.h"
#include "models/model_file.h"
#include "render_data/dataset.h"

namespace cgsr {

config::Schema<PruneCommandOptions> prune_command_schema() {
  config::Schema<PruneCommandOptions> s;
  s.field("model", &PruneCommandOptions::model, "elastic model file the search ran on").required();
  s.field("search", &PruneCommandOptions::search, "results.json of the search over its subnets").required();
  s.field("data", &PruneCommandOptions::data, "data set directory of the scene").required();
  add_prune_fields(s);
  s.field("resume", &PruneCommandOptions::resume, "continue the fine-tuning from the run directory's checkpoints");
  add_run_settings(s);
  return s;
}

nlohmann::ordered_json run_prune(const PruneCommandOptions& options, const YAML::Node& resolved, RunDir& run_dir) {
  // What the network and the dynamic pruning component's sampler read, nothing more.
  std::vector<RenderChannel> channels = read_model_file(options.model).spec.input_channels();
  for (auto c : options.sampler.render_channels()) channels.push_back(c);
  const Dataset data = open_for_channels(options.data, channels);
  return prune(options.model, options.search, data, options, run_dir.path(), options.resume, yaml_to_json(resolved));
}

}  // namespace cgsr
