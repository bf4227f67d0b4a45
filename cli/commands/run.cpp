#include "cli/commands/run.h"

#include <filesystem>
#include <memory>

#include "cli/command.h"
#include "core/text.h"
#include "models/memory_layout.h"
#include "pipeline/pipeline.h"

namespace fs = std::filesystem;

namespace cgsr::cli {

namespace {
// The default directory is stable (runs/<name>), so that a rerun finds its finished stages.
fs::path run_root(const PipelineOptions& options) {
  return globals().out.empty() ? fs::path("runs") / options.name : fs::path(globals().out);
}
}  // namespace

void setup_run(CLI::App& app) {
  add_command<PipelineOptions>(
      app, "run", "The whole pipeline: render, train, CG-enhance, search, prune, export, evaluate, report",
      pipeline_schema,
      [](CLI::App& sub, std::vector<FlagAssignment>& flags) {
        flag_to_key(sub, flags, "--from", "from", "rerun this stage and every later one (" + join(pipeline_stages()) + ")");
        // --data replaces the config's scene (the config may name either, not both).
        sub.add_option_function<std::string>(
            "--data",
            [&flags](const std::string& dir) {
              flags.push_back({"scene=''", "--data " + dir});
              flags.push_back({"data=" + dir, "--data " + dir});
            },
            "use this data set instead of rendering the config's scene (config key 'data')");
      },
      [](const PipelineOptions& options, const YAML::Node& resolved, RunDir* run_dir) {
        const fs::path dir = run_root(options);
        std::unique_ptr<RunDirLock> lock;
        std::unique_ptr<RunDir> own;
        if (!run_dir) {
          lock = std::make_unique<RunDirLock>(dir, "run", globals().force);
          own = std::make_unique<RunDir>(dir);
          own->write_config(resolved);
        }
        // At the root, so that a stage that reruns (and starts from an empty directory) keeps them.
        LayoutRecordScope layouts(dir / "layouts.json");
        return run_pipeline(options, resolved, dir);
      },
      /*always_run_dir=*/false, /*place_run_dir=*/{},
      [](const PipelineOptions& options) { return check_pipeline(options, run_root(options)); });
}

}  // namespace cgsr::cli
