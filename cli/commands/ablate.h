#pragma once
// `cgsr ablate`: does rendering information pay? From one trained plain network, trains the
// control (the plain network trained on as long), every RIT source, the best source with each
// channel left out and a small network with and without it, over several seeds
// (pipeline/ablation.h). Writes ablation.md, ablation.csv, ablation.png and results.json; each
// (variant, seed) keeps its model and record under variants/, so a rerun resumes.

#include <CLI/CLI.hpp>

#include "cli/command.h"
#include "pipeline/ablation.h"

namespace cgsr::cli {

struct AblateOptions : RunSettings {
  std::string data;   // data set directory (required)
  std::string model;  // the trained plain network (model file, required)
  AblationOptions ablation;
};

config::Schema<AblateOptions> ablate_schema();
void setup_ablate(CLI::App& app);
nlohmann::ordered_json run_ablate(const AblateOptions& options, RunDir& run_dir);

}  // namespace cgsr::cli
