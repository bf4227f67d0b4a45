#pragma once
// The prune job: what `cgsr prune` runs, and the prune stage of `cgsr run`. Hybrid pruning among
// the subnets a search found in an elastic network (pruning/pruner.h). Writes pruned.cgsr (the
// statically pruned network with its dynamic pruning component), pool.json, the fine-tuning
// checkpoint (for --resume) and results.json: `roles` names each model and its file, and
// `evaluations` (the search's pick, the static network, the hybrid model) feed `cgsr report`.

#include <nlohmann/json.hpp>

#include "core/run_dir.h"
#include "pipeline/run_settings.h"
#include "pruning/pruner.h"

namespace cgsr {

struct PruneCommandOptions : RunSettings, PruneOptions {
  std::string model;    // the elastic model file the search ran on (required)
  std::string search;   // the search's results.json (required)
  std::string data;     // data set directory (required)
  bool resume = false;  // continue the fine-tuning from the run directory's checkpoints
};

config::Schema<PruneCommandOptions> prune_command_schema();
nlohmann::ordered_json run_prune(const PruneCommandOptions& options, const YAML::Node& resolved, RunDir& run_dir);

}  // namespace cgsr
