#pragma once
// Hybrid pruning of a trained network for one scene (the paper's second phase), end to end:
//
//   1. per training frame, channel importance (Taylor by default); the network's channels are
//      reordered by it, and the pool of nested patterns built (pattern_pool.h)
//   2. fine-tuning of every pattern by the sandwich rule with L_p (dynamic_pruning.h)
//   3. the dynamic pruning component fitted to choose, per frame, the cheapest pattern that
//      does not cost the frame quality, within the budget (dynamic_pruning.h)
//   4. static pruning of the patterns no training frame selects (static_pruning.h), and the
//      latency table of the remaining ones
//   5. the static baselines (baseline_pruning.h; magnitude pruning by default), each at the
//      hybrid model's mean MACs on the training frames unless given a rate, fine-tuned with the
//      same number of steps
//   6. evaluation of the input model, the baselines, the static network alone and the hybrid
//      model on held-out frames, through the same evaluate() as `cgsr eval`
// Writes <out>/pruned.cgsr (hybrid; plain load_model() reads its static network), one
// baseline<i>_<type>.cgsr per baseline and pool.json, and returns the results: `roles` says
// which evaluated model is which and where its file is (PruneRoles), and the `evaluations`
// list feeds `cgsr report`.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <type_traits>
#include <utility>

#include "core/config.h"
#include "core/json_fields.h"
#include "eval/evaluation.h"
#include "models/importance/importance_methods.h"
#include "models/model_file.h"
#include "pruning/baseline_pruning.h"
#include "pruning/dynamic_pruning.h"
#include "pruning/dynamic_sampler.h"
#include "pruning/pattern_pool.h"
#include "pruning/static_pruning.h"
#include "render_data/dataset.h"

namespace cgsr {

struct PruneOptions {
  std::string name;                 // display name of the input model (default: recorded name or file stem)
  std::string importance = "taylor";  // a method of models/importance/importance_methods.h
  int pool_frames = 0;              // training frames whose importance orders the channels (0 = all)
  PoolOptions pool;
  SamplerOptions sampler;
  FinetuneOptions finetune;
  SelectorOptions selector;
  StaticPruneOptions static_prune;
  std::vector<BaselineOptions> baselines = {BaselineOptions{}};
  EvalOptions eval;                 // held-out evaluation of every model
};

// Which evaluated model of a prune run is which, and its file: callers join results by role,
// never by display name.
struct PrunedModel {
  std::string name;            // display name in the evaluations
  std::filesystem::path file;  // its model file
};
CGSR_JSON_FIELDS(PrunedModel, name, file)
struct PrunedBaseline : PrunedModel {
  BaselineOptions options;
  double keep_rate = 0;  // the rate used (matched to the hybrid's MACs when options.keep_rate is 0)
};
struct PruneRoles {
  PrunedModel input;                     // the network that was pruned
  PrunedModel hybrid;                    // the hybrid model (pruned.cgsr)
  PrunedModel static_network;            // its static network alone (the same file, load_model)
  std::vector<PrunedBaseline> baselines;
  // The first baseline of `type`, or null.
  const PrunedBaseline* baseline(const std::string& type) const;
};
nlohmann::ordered_json to_json(const PruneRoles& roles);
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
  s.field("name", m(&PruneOptions::name), "display name of the input model in reports (default: the recorded one)");
  s.field("importance", m(&PruneOptions::importance), "channel importance that orders the pattern pool's channels")
      .one_of(importance_methods().names());
  s.field("pool_frames", m(&PruneOptions::pool_frames),
          "training frames whose channel importance orders the channels (0 = all)")
      .at_least(0);
  s.section("pool", m(&PruneOptions::pool), pool_schema(), "pattern pool (nested channel widths)");
  s.section("sampler", m(&PruneOptions::sampler), sampler_schema(), "the dynamic pruning component's sampler");
  s.section("finetune", m(&PruneOptions::finetune), finetune_schema(),
            "fine-tuning of every pattern with L_p (Eq. 4, sandwich rule)");
  s.section("selector", m(&PruneOptions::selector), selector_schema(), "fitting the per-frame pattern choice");
  s.section("static", m(&PruneOptions::static_prune), static_prune_schema(), "static pruning");
  s.list("baselines", m(&PruneOptions::baselines), baseline_schema(),
         "static pruning baselines, fine-tuned with the same steps (default: magnitude pruning at the hybrid's MACs)");
  s.section("eval", m(&PruneOptions::eval), eval_schema_fields(), "held-out evaluation of every model");
}

// `model_path`: the trained model file. `out`: an existing directory for the artifacts and
// fine-tuning checkpoints (resumed when `resume`). `config`: recorded in the models' provenance.
nlohmann::ordered_json prune(const std::filesystem::path& model_path, const Dataset& data, const PruneOptions& options,
                             const std::filesystem::path& out, bool resume,
                             const nlohmann::ordered_json& config = nlohmann::ordered_json::object());

}  // namespace cgsr
