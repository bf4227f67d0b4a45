#pragma once
// `cgsr train`: trains a plain backbone or a CG-enhanced network (the train job:
// pipeline/train_stage.h). Here: its flags, and a distributed rank's own run directory.

#include <CLI/CLI.hpp>

namespace cgsr::cli {

void setup_train(CLI::App& app);

}  // namespace cgsr::cli
