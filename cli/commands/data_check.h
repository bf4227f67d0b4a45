#pragma once
// `cgsr data check DIR`: validates a dataset (every frame at every resolution, sizes consistent
// with the scale, no NaN/Inf, value ranges) and prints a summary with counts. Exits with code 2
// when problems were found. `cgsr data` is the group; `setup_data` adds it with its
// subcommands (check, preview, merge).

#include <CLI/CLI.hpp>

#include "cli/command.h"
#include "render_data/dataset.h"

namespace cgsr::cli {

struct DataCheckOptions : RunSettings {
  std::string dir;                 // dataset directory or glob-layout YAML (positional)
  DatasetOpenOptions open;         // layout, derive, clean_grid_lines, near/far, ...
  int max_messages = 20;           // problems listed in full
  bool json = false;
};

config::Schema<DataCheckOptions> data_check_schema();
// Adds `data` with its subcommands to `app`.
void setup_data(CLI::App& app);
void setup_data_check(CLI::App& data);
// Prints the summary; throws cgsr::Error (exit 2) when problems were found.
nlohmann::ordered_json run_data_check(const DataCheckOptions& options);

}  // namespace cgsr::cli
