#pragma once
// The search job: what `cgsr search` runs, and the search stage of `cgsr run`. The CG-guided
// architecture search starts from a CG-enhanced model file, evolves smaller specs
// (search/search_loop.h), trains the pick longer and writes it as model.cgsr. history.jsonl
// records every candidate and is the checkpoint of resume.

#include <nlohmann/json.hpp>

#include "core/run_dir.h"
#include "distributed/world.h"
#include "pipeline/run_settings.h"
#include "pipeline/training_evaluator.h"
#include "search/search_loop.h"

namespace cgsr {

struct SearchCommandOptions : RunSettings {
  std::string parent;  // CG-enhanced model file (required)
  std::string data;    // data set directory (required)
  SearchOptions search;  // its keys sit at the top level of the config
  CandidateTraining candidate;
  TrainSchedule final_schedule;  // training of the pick (paper: 30 epochs)
  std::string name;              // display name of the result
  bool resume = false;
  distributed::DistributedOptions distributed;  // candidates spread over processes (docs/distributed.md)
};

config::Schema<SearchCommandOptions> search_command_schema();

// A resolved `cgsr search` config in the shape it had before the search options moved to the top
// level and each strategy got its own options block (`search: {strategy: evolution, operators:
// {...}}`): the search stage of `cgsr run` hashes this form, so run directories made before stay
// current when nothing but the shape changed.
YAML::Node search_config_cache_form(const YAML::Node& resolved);
nlohmann::ordered_json run_search_command(const SearchCommandOptions& options, const YAML::Node& resolved,
                                          RunDir& run_dir);

}  // namespace cgsr
