#pragma once
// `cgsr search`: the CG-guided architecture search (the search job:
// pipeline/search_stage.h). Here: its flags, and a distributed rank's own run directory.

#include <CLI/CLI.hpp>

namespace cgsr::cli {

void setup_search(CLI::App& app);

}  // namespace cgsr::cli
