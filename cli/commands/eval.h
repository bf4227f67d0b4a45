#pragma once
// `cgsr eval`: evaluates model files and classic upscalers on a data set split (the eval job:
// pipeline/eval_stage.h). Here: its flags.

#include <CLI/CLI.hpp>

namespace cgsr::cli {

void setup_eval(CLI::App& app);

}  // namespace cgsr::cli
