#include "cli/commands/export.h"

#include "cli/command.h"
#include "pipeline/export_stage.h"

namespace cgsr::cli {

void setup_export(CLI::App& app) {
  add_command<ExportCommandOptions>(
      app, "export", "Export a network as ONNX or TorchScript, optionally verified in other runtimes", export_schema,
      [](CLI::App& sub, std::vector<FlagAssignment>& flags) {
        flag_to_key(sub, flags, "--model", "model", "backbone name, spec YAML file or model file");
        flag_to_key(sub, flags, "--scale", "scale", "scale for a backbone name");
        flag_to_key(sub, flags, "--format", "format", "onnx or torchscript");
        flag_to_key(sub, flags, "--input", "input", "LR input size WxH");
        switch_to_key(sub, flags, "--dynamic-size", "dynamic_size", "ONNX: symbolic batch, height and width");
        flag_to_key(sub, flags, "--cubic-resize", "cubic_resize", "ONNX bicubic resize: conv or native");
        switch_to_key(sub, flags, "--verify", "verify", "verify in other runtimes against our forward pass");
        flag_to_key(sub, flags, "--tolerance", "tolerance", "max abs error allowed by --verify");
        flag_to_key(sub, flags, "--out", "out", "the file to write (a directory for a hybrid-pruned model)");
        flag_to_key(sub, flags, "--precision", "precision", "fp32, or int8 (quantized ONNX, calibrated on --data)");
        flag_to_key(sub, flags, "--data", "data", "data set whose frames calibrate int8 and, with --verify, verify the file");
        flag_to_key(sub, flags, "--frames", "frames", "--verify: frames A:B of --data, run in order (default: the first test frame)");
      },
      [](const ExportCommandOptions& options, const YAML::Node&, RunDir*) { return run_export(options); },
      /*always_run_dir=*/false);
}

}  // namespace cgsr::cli
