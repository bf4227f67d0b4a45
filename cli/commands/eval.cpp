#include "cli/commands/eval.h"

#include "cli/command.h"
#include "pipeline/eval_stage.h"

namespace cgsr::cli {

void setup_eval(CLI::App& app) {
  add_command<EvalCommandOptions>(
      app, "eval", "Evaluate models and classic upscalers: PSNR, SSIM, temporal error, latency", eval_schema,
      [](CLI::App& sub, std::vector<FlagAssignment>& flags) {
        flag_to_key(sub, flags, "--data", "data", "data set directory");
        list_to_key(sub, flags, "--model", "models",
                    "model file or classic upscaler name (repeatable; 'classic' = all classic upscalers)", "--model");
        flag_to_key(sub, flags, "--scene", "scene", "one scene of a multi-scene data set");
        flag_to_key(sub, flags, "--split", "eval.split", "data set split");
        flag_to_key(sub, flags, "--scale", "scale", "scale of the classic upscalers");
        flag_to_key(sub, flags, "--crop-border", "eval.crop_border", "HR pixels ignored at each border");
        flag_to_key(sub, flags, "--save-frames", "eval.save_frames", "directory for upscaled frames");
        flag_to_key(sub, flags, "--save-images", "images.frames",
                    "crops and error maps of the N frames with the most geometry edges, into images/");
        flag_to_key(sub, flags, "--frames", "eval.frames", "frame index range A:B within the split");
        flag_to_key(sub, flags, "--latency-runs", "eval.latency_runs", "timed runs for latency (0 = skip)");
        list_to_key(sub, flags, "--precision", "precisions",
                    "number formats each network runs in (fused engine): fp32, bf16, int8", "PRECISION");
      },
      [](const EvalCommandOptions& options, const YAML::Node&, RunDir* run_dir) { return run_eval(options, run_dir); },
      /*always_run_dir=*/true);
}

}  // namespace cgsr::cli
