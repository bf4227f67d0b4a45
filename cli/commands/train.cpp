#include "cli/commands/train.h"

#include "cli/command.h"
#include "pipeline/distributed_run.h"
#include "pipeline/train_stage.h"

namespace cgsr::cli {

void setup_train(CLI::App& app) {
  add_command<TrainOptions>(
      app, "train", "Train a backbone or a CG-enhanced network", train_schema,
      [](CLI::App& sub, std::vector<FlagAssignment>& flags) {
        flag_to_key(sub, flags, "--data", "data", "data set directory");
        flag_to_key(sub, flags, "--model", "model", "backbone name, spec file or model file");
        flag_to_key(sub, flags, "--steps", "schedule.steps", "optimizer steps");
        switch_to_key(sub, flags, "--resume", "resume", "continue from the run directory's checkpoint");
        add_distributed_flags(sub, flags);
      },
      [](const TrainOptions& options, const YAML::Node& resolved, RunDir* run_dir) {
        TrainOptions forced = options;
        forced.force_resume = globals().force;
        return run_train(forced, resolved, *run_dir);
      },
      /*always_run_dir=*/true,
      [](const TrainOptions& options, const std::filesystem::path& out) {
        return rank_run_dir(options.distributed, out);
      },
      check_train);
}

}  // namespace cgsr::cli
