#include "cli/commands/render.h"

#include "cli/command.h"
#include "pipeline/render_stage.h"

namespace cgsr::cli {

void setup_render(CLI::App& app) {
  add_command<RenderOptions>(
      app, "render", "Render a scene config into a dataset (LR/HR colour, depth, normals, edges, motion)",
      render_schema,
      [](CLI::App& sub, std::vector<FlagAssignment>& flags) {
        flag_to_key(sub, flags, "--frames", "frames", "frames to render");
        flag_to_key(sub, flags, "--resolutions", "resolutions", "resolutions, e.g. [320x240,640x480]");
        sub.add_option_function<std::vector<std::string>>(
            "--scene",
            [&flags](const std::vector<std::string>& configs) {
              std::string list = "[";
              for (size_t i = 0; i < configs.size(); ++i) list += (i ? ", " : "") + ("{config: '" + configs[i] + "'}");
              flags.push_back({"scenes=" + list + "]", "--scene"});
            },
            "a scene config to render into the data set (repeatable: a scene set; config key 'scenes')");
      },
      [](const RenderOptions& options, const YAML::Node&, RunDir* run_dir) {
        return run_render(options, *run_dir);
      },
      /*always_run_dir=*/true, /*place_run_dir=*/{}, check_render);
}

}  // namespace cgsr::cli
