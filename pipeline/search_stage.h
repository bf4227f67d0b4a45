#pragma once
// The search job: what `cgsr search` runs, and the search stage of `cgsr run`: the CG-guided
// architecture search over the subnets of an elastic network (one trained with `cgsr train` and
// `elastic.enabled`). Evolution (NSGA-II) scores subnets by
// inference on validation crops against the latency table stored with the network, and random
// search with as many evaluations is its control; both fronts, their hypervolumes and a plot are
// written. The pick, the best subnet within the latency budget (predicted, then checked by
// measurement against a reference network's, as the report times them: eval/relative_latency.h),
// is materialized as a network of its own and fine-tuned with distillation from the full network:
// model.cgsr.
// history.jsonl (and random_history.jsonl) record every subnet and are the checkpoint of --resume.

#include <nlohmann/json.hpp>

#include "core/run_dir.h"
#include "pipeline/run_settings.h"
#include "search/search_loop.h"
#include "search/subnet_evaluator.h"
#include "train/losses.h"
#include "train/trainer.h"

namespace cgsr {

struct PickOptions {
  double latency_fraction = 0.33;  // budget: this fraction of the reference's latency (predicted, then measured)
  double latency_ms = 0;           // or this many ms (when > 0)
  // The model file the fraction is of ("": the full network). `cgsr run` names its backbone
  // (PAN x2), the network the verdict's latency check divides by.
  std::string reference;
  int measure_runs = 5;            // timed runs per subnet when the pick is checked by measurement (0: not)
};

struct FinalTraining {
  TrainSchedule schedule;  // fine-tuning of the pick
  LossOptions loss;
  double distill = 1.0;    // weight of the full network's output beside the HR frame's 1
};

struct SearchCommandOptions : RunSettings {
  std::string model;  // elastic model file (required)
  std::string data;   // data set directory (required)
  SearchOptions search;                    // its keys sit at the top level of the config
  std::string baseline = "random";         // a strategy run with as many evaluations ("": none)
  ValidationCropOptions crops;
  PickOptions pick;
  FinalTraining final;
  std::string name;   // display name of the result
  bool resume = false;
};

config::Schema<SearchCommandOptions> search_command_schema();
nlohmann::ordered_json run_search_command(const SearchCommandOptions& options, const YAML::Node& resolved,
                                          RunDir& run_dir);

}  // namespace cgsr
