#pragma once
// `cgsr export`: writes a network as ONNX or TorchScript, optionally verified in other runtimes
// (the export job: pipeline/export_stage.h). Here: its flags; --out names the exported file
// (the command writes no run directory).

#include <CLI/CLI.hpp>

namespace cgsr::cli {

void setup_export(CLI::App& app);

}  // namespace cgsr::cli
