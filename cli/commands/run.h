#pragma once
// `cgsr run --config configs/quickstart.yaml`: the whole CGSR pipeline in one command
// (pipeline/pipeline.h: its stages, their directories and caching). Here: its flags, and the run
// directory, --out or runs/<name> (stable, so that a rerun finds its finished stages).

#include <CLI/CLI.hpp>

namespace cgsr::cli {

void setup_run(CLI::App& app);

}  // namespace cgsr::cli
