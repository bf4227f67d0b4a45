#pragma once
// Hybrid pruning of a trained network for one scene (the paper's second phase), end to end:
//
//   1. units (prunable_units.h) and, per training frame, channel importance (Taylor by default)
//   2. the pattern pool by frequency-based sorting (pattern_pool.h)
//   3. dynamic samplers warmed up on each frame's pool entry, then fine-tuning of network and
//      samplers with L_p (dynamic_pruning.h), `finetune.epochs` epochs (paper: 2)
//   4. static pruning of what no training frame selects (static_pruning.h)
//   5. the magnitude pruning baseline at the per-frame rate, fine-tuned with the same budget
//   6. evaluation of the input model, the baseline, the static network alone and the hybrid
//      model on held-out frames, through the same evaluate() as `cgsr eval`
// Writes <out>/pruned.cgsr (hybrid; plain load_model() reads its static network), mmp.cgsr,
// pool.json, and returns the results (the `evaluations` list feeds `cgsr report`).

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <type_traits>
#include <utility>

#include "core/config.h"
#include "models/model_file.h"
#include "pruning/dynamic_pruning.h"
#include "pruning/dynamic_sampler.h"
#include "pruning/pattern_pool.h"
#include "pruning/static_pruning.h"
#include "render_data/dataset.h"
#include "train/evaluation.h"

namespace cgsr {

struct PruneOptions {
  std::string name;                 // display name of the input model (default: recorded name or file stem)
  std::string importance = "taylor";  // taylor | activation
  int pool_frames = 0;              // training frames ranked for the pool and the warm-up (0 = all)
  PoolOptions pool;
  SamplerOptions sampler;
  int warmup_steps = 300;           // sampler warm-up steps (full batch of the pool frames)
  double warmup_lr = 1e-2;
  FinetuneOptions finetune;
  StaticPruneOptions static_prune;
  bool magnitude_baseline = true;
  EvalOptions eval;                 // held-out evaluation of every model
};

// Binds the PruneOptions fields of an options struct T deriving from PruneOptions (a command's)
// at the top level of its config, next to T's own keys.
template <class T>
void add_prune_fields(config::Schema<T>& s) {
  const auto m = [](auto PruneOptions::*member) {
    using V = std::remove_reference_t<decltype(std::declval<PruneOptions&>().*member)>;
    return static_cast<V T::*>(member);
  };
  s.field("name", m(&PruneOptions::name), "display name of the input model in reports (default: the recorded one)");
  s.field("importance", m(&PruneOptions::importance), "per-frame channel importance for the pattern pool")
      .one_of({"taylor", "activation"});
  s.field("pool_frames", m(&PruneOptions::pool_frames), "training frames ranked for the pattern pool (0 = all)")
      .at_least(0);
  s.section("pool", m(&PruneOptions::pool), pool_schema(), "pattern pool (frequency-based sorting)");
  s.section("sampler", m(&PruneOptions::sampler), sampler_schema(), "dynamic samplers of the pruning components");
  s.field("warmup_steps", m(&PruneOptions::warmup_steps), "sampler warm-up steps before fine-tuning")
      .range(0, 100000);
  s.field("warmup_lr", m(&PruneOptions::warmup_lr), "sampler warm-up learning rate").range(1e-9, 10);
  s.section("finetune", m(&PruneOptions::finetune), finetune_schema(), "fine-tuning with L_p (Eq. 4)");
  s.section("static", m(&PruneOptions::static_prune), static_prune_schema(), "static pruning");
  s.field("magnitude_baseline", m(&PruneOptions::magnitude_baseline),
          "also prune by L1 magnitude at the same per-frame rate, fine-tuned with the same budget (MMP)");
  s.section("eval", m(&PruneOptions::eval), eval_schema_fields(), "held-out evaluation of every model");
}

// `model_path`: the trained model file. `out`: an existing directory for the artifacts and
// fine-tuning checkpoints (resumed when `resume`). `config`: recorded in the models' provenance.
nlohmann::ordered_json prune(const std::filesystem::path& model_path, const Dataset& data, const PruneOptions& options,
                             const std::filesystem::path& out, bool resume,
                             const nlohmann::ordered_json& config = nlohmann::ordered_json::object());

}  // namespace cgsr
