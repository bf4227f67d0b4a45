#include "cli/commands/prune.h"

#include "cli/command.h"
#include "pipeline/prune_stage.h"

namespace cgsr::cli {

void setup_prune(CLI::App& app) {
  add_command<PruneCommandOptions>(
      app, "prune",
      "Rendering-aware hybrid pruning: subnets of the search's front, a per-frame choice from rendering information, "
      "static pruning",
      prune_command_schema,
      [](CLI::App& sub, std::vector<FlagAssignment>& flags) {
        flag_to_key(sub, flags, "--model", "model", "elastic model file the search ran on");
        flag_to_key(sub, flags, "--search", "search", "the search's results.json");
        flag_to_key(sub, flags, "--data", "data", "data set directory");
        flag_to_key(sub, flags, "--budget", "selector.budget",
                    "mean per-frame cost of the chosen patterns, as a fraction of the widest pattern's");
        flag_to_key(sub, flags, "--steps", "finetune.schedule.steps", "fine-tuning steps of the patterns");
        switch_to_key(sub, flags, "--resume", "resume", "continue an interrupted run in --out");
      },
      [](const PruneCommandOptions& options, const YAML::Node& resolved, RunDir* run_dir) {
        return run_prune(options, resolved, *run_dir);
      },
      /*always_run_dir=*/true);
}

}  // namespace cgsr::cli
