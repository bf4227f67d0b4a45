#pragma once
// `cgsr prune`: hybrid pruning of a trained model for one scene (the prune job:
// pipeline/prune_stage.h). Here: its flags.

#include <CLI/CLI.hpp>

namespace cgsr::cli {

void setup_prune(CLI::App& app);

}  // namespace cgsr::cli
