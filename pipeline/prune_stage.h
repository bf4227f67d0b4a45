#pragma once
// The prune job: what `cgsr prune` runs, and the prune stage of `cgsr run`. Hybrid pruning of a
// trained model for one scene (pruning/pruner.h). Writes
// pruned.cgsr (the statically pruned network with its dynamic pruning component), one
// baseline<i>_<type>.cgsr per static baseline (magnitude pruning by default), pool.json,
// fine-tuning checkpoints (for --resume) and results.json: `roles` names each model and its
// file, and `evaluations` (input model, baselines, static, hybrid) feed `cgsr report`.

#include <nlohmann/json.hpp>

#include "core/run_dir.h"
#include "pipeline/run_settings.h"
#include "pruning/pruner.h"

namespace cgsr {

struct PruneCommandOptions : RunSettings, PruneOptions {
  std::string model;    // trained model file (required)
  std::string data;     // data set directory (required)
  bool resume = false;  // continue the fine-tuning from the run directory's checkpoints
};

config::Schema<PruneCommandOptions> prune_command_schema();
nlohmann::ordered_json run_prune(const PruneCommandOptions& options, const YAML::Node& resolved, RunDir& run_dir);

}  // namespace cgsr
