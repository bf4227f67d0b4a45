#include "cli/commands/search.h"

#include "cli/command.h"
#include "pipeline/distributed_run.h"
#include "pipeline/search_stage.h"

namespace cgsr::cli {

void setup_search(CLI::App& app) {
  add_command<SearchCommandOptions>(
      app, "search", "CG-guided evolutionary architecture search (CG-enhanced -> CG-optimized)",
      search_command_schema,
      [](CLI::App& sub, std::vector<FlagAssignment>& flags) {
        flag_to_key(sub, flags, "--parent", "parent", "CG-enhanced model file");
        flag_to_key(sub, flags, "--data", "data", "data set directory");
        flag_to_key(sub, flags, "--strategy", "strategy", "evolution or random (with its default options)");
        switch_to_key(sub, flags, "--resume", "resume", "continue an interrupted search in --out");
        add_distributed_flags(sub, flags);
      },
      [](const SearchCommandOptions& options, const YAML::Node& resolved, RunDir* run_dir) {
        return run_search_command(options, resolved, *run_dir);
      },
      /*always_run_dir=*/true,
      [](const SearchCommandOptions& options, const std::filesystem::path& out) {
        return rank_run_dir(options.distributed, out);
      });
}

}  // namespace cgsr::cli
