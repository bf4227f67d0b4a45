#pragma once
// Hybrid pruning (the paper's second phase) over the subnets of an elastic network, end to end:
//
//   1. the pattern pool: points of the search's Pareto front around its pick (pattern_pool.h),
//      all subnets of one elastic network, some wider and some narrower than the pick
//   2. the network that holds them (their union) with every pattern fine-tuned at once,
//      distilled from the full elastic network, for as many steps as the pick was
//   3. the dynamic pruning component fitted to choose, per frame, the cheapest pattern that does
//      not cost the frame quality, on average at the pick's predicted latency (dynamic_pruning.h)
//   4. static pruning of the patterns no training frame selects (static_pruning.h), and the
//      measured latency of the remaining ones
//   5. evaluation of the pick (the CG-optimized network), the static network alone and the
//      hybrid model on held-out frames, through the same evaluate() as `cgsr eval`
// Writes <out>/pruned.cgsr (hybrid; plain load_model() reads its static network) and pool.json,
// and returns the results: `roles` says which evaluated model is which and where its file is
// (PruneRoles), and the `evaluations` list feeds `cgsr report`.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <type_traits>
#include <utility>

#include "core/config.h"
#include "core/json_fields.h"
#include "eval/evaluation.h"
#include "models/model_file.h"
#include "pruning/dynamic_pruning.h"
#include "pruning/dynamic_sampler.h"
#include "pruning/pattern_pool.h"
#include "render_data/dataset.h"
#include "train/losses.h"
#include "train/trainer.h"

namespace cgsr {

// The fine-tuning of every pattern at once (the search's fine-tuning of the pick, for the pool).
struct PoolTraining {
  TrainSchedule schedule;
  LossOptions loss;
  double distill = 1.0;    // weight of the full elastic network's output beside the HR frame's
};
config::Schema<PoolTraining> pool_training_schema();

struct PruneOptions {
  std::string name;  // display name of the pick (default: the one its file records)
  PoolOptions pool;
  PoolTraining finetune;
  SamplerOptions sampler;
  SelectorOptions selector;
  EvalOptions eval;  // held-out evaluation of every model
};

// Which evaluated model of a prune run is which, and its file: callers join results by role,
// never by display name.
struct PrunedModel {
  std::string name;            // display name in the evaluations
  std::filesystem::path file;  // its model file
};
CGSR_JSON_FIELDS(PrunedModel, name, file)
struct PruneRoles {
  PrunedModel input;           // the search's pick (the CG-optimized network)
  PrunedModel hybrid;          // the hybrid model (pruned.cgsr)
  PrunedModel static_network;  // its static network alone (the same file, load_model)
};
CGSR_JSON_FIELDS(PruneRoles, input, hybrid, static_network)
// `where` names the results file in errors.
PruneRoles prune_roles_from_json(const nlohmann::ordered_json& j, const std::string& where);

// Binds the PruneOptions fields of an options struct T deriving from PruneOptions (a command's)
// at the top level of its config, next to T's own keys.
template <class T>
void add_prune_fields(config::Schema<T>& s) {
  const auto m = [](auto PruneOptions::*member) {
    using V = std::remove_reference_t<decltype(std::declval<PruneOptions&>().*member)>;
    return static_cast<V T::*>(member);
  };
  s.field("name", m(&PruneOptions::name), "display name of the pick in reports (default: the recorded one)");
  s.section("pool", m(&PruneOptions::pool), pool_schema(), "the patterns: points of the search's front");
  s.section("finetune", m(&PruneOptions::finetune), pool_training_schema(),
            "fine-tuning of every pattern at once, distilled from the full elastic network");
  s.section("sampler", m(&PruneOptions::sampler), sampler_schema(), "the dynamic pruning component's sampler");
  s.section("selector", m(&PruneOptions::selector), selector_schema(), "fitting the per-frame pattern choice");
  s.section("eval", m(&PruneOptions::eval), eval_schema_fields(), "held-out evaluation of every model");
}

// `elastic`: the elastic model file the search ran on; `search`: the search's results.json
// (front, pick and the pick's model file). `out`: an existing directory for the artifacts and
// the fine-tuning checkpoint (resumed when `resume`). `config`: recorded in the provenance.
nlohmann::ordered_json prune(const std::filesystem::path& elastic, const std::filesystem::path& search,
                             const Dataset& data, const PruneOptions& options, const std::filesystem::path& out,
                             bool resume, const nlohmann::ordered_json& config = nlohmann::ordered_json::object());

}  // namespace cgsr
