#pragma once
// `cgsr info`: what this build and machine are (library versions, threads, SIMD level).

#include <CLI/CLI.hpp>

#include "cli/command.h"

namespace cgsr::cli {

struct InfoOptions : RunSettings {
  bool json = false;  // print JSON instead of a table
};

config::Schema<InfoOptions> info_schema();
void setup_info(CLI::App& app);
nlohmann::ordered_json run_info(const InfoOptions& options);

}  // namespace cgsr::cli
