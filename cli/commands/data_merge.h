#pragma once
// `cgsr data merge A B [...] --out DIR`: one multi-scene data set from existing ones, without
// copying frames: DIR/manifest.yaml lists the scenes of A, B, ... by path (dataset_manifest.h).
// Training, search, pruning and evaluation then take DIR like any data set. Optional weights, one
// per data set: `--set weights=[1,2]`.

#include <CLI/CLI.hpp>

#include "cli/command.h"

namespace cgsr::cli {

struct DataMergeOptions : RunSettings {
  std::vector<std::string> data;  // data set directories (positional)
  std::vector<double> weights;    // one per data set, or none
  std::string name;               // empty: the scene names joined by '+'
};

config::Schema<DataMergeOptions> data_merge_schema();
void setup_data_merge(CLI::App& data);
// Merges into the run directory; its manifest is written once its results.json is.
nlohmann::ordered_json run_data_merge(const DataMergeOptions& options, RunDir& run_dir);

}  // namespace cgsr::cli
