#pragma once
// `cgsr info`: what this build and machine are (library versions, threads, SIMD level) and,
// with --model, a network's layers, parameters and multiply-accumulates for an input size.

#include <CLI/CLI.hpp>

#include "cli/command.h"

namespace cgsr::cli {

struct InfoOptions : RunSettings {
  bool json = false;   // print JSON instead of a table
  std::string model;   // backbone name, spec YAML or model file; "" = system information only
  int scale = 0;       // 0: the model file's scale, or 2 for a backbone name
  std::string input;   // LR input "WxH"; "" = the LR size of a 1280x720 output
};

config::Schema<InfoOptions> info_schema();
void setup_info(CLI::App& app);
nlohmann::ordered_json run_info(const InfoOptions& options);

}  // namespace cgsr::cli
