#include "cli/commands/search.h"

#include "cli/command.h"
#include "pipeline/search_stage.h"

namespace cgsr::cli {

void setup_search(CLI::App& app) {
  add_command<SearchCommandOptions>(
      app, "search", "Evolutionary search over the subnets of an elastic network (CG-enhanced -> CG-optimized)",
      search_command_schema,
      [](CLI::App& sub, std::vector<FlagAssignment>& flags) {
        flag_to_key(sub, flags, "--model", "model", "elastic model file");
        flag_to_key(sub, flags, "--data", "data", "data set directory");
        flag_to_key(sub, flags, "--strategy", "strategy", "evolution or random (with its default options)");
        switch_to_key(sub, flags, "--resume", "resume", "continue an interrupted search in --out");
      },
      [](const SearchCommandOptions& options, const YAML::Node& resolved, RunDir* run_dir) {
        return run_search_command(options, resolved, *run_dir);
      },
      /*always_run_dir=*/true);
}

}  // namespace cgsr::cli
