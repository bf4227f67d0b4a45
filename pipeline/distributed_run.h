#pragma once
// What the search and train jobs share when they run as several processes (distributed/):
// where a rank writes its run directory, and the check that every rank was started on the same
// job.

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <memory>
#include <string>

#include "distributed/world.h"

namespace cgsr {

// Rank 0 writes into --out itself; rank R > 0 into --out/rank<R> (its log and results), so N
// processes on one machine can share one --out.
std::filesystem::path rank_run_dir(const distributed::DistributedOptions& options, const std::filesystem::path& out);

// Joins the run and compares `job` (a text naming everything a rank's results depend on) and
// the thread count over the ranks: a different job is an error naming the rank; a different
// thread count a warning (results then match a 1-process run only within float tolerance).
std::unique_ptr<distributed::World> join_run(const distributed::DistributedOptions& options,
                                              const std::string& job);

// A stage's resolved config without its `distributed` block, for the stage cache of `cgsr run`:
// how many processes ran a stage does not change its result.
YAML::Node without_distribution(const YAML::Node& resolved);

}  // namespace cgsr
