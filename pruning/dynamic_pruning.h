#pragma once
// Training the dynamic pruning of a network on a data set, in two steps:
//
//   1. hooks(): the Trainer fine-tunes the network so that every nested pattern of the pool
//      (pattern_pool.h) works on its own, by the sandwich rule: each step trains the widest
//      pattern (the trainer's own loss), the narrowest and `sampled_patterns` others drawn per
//      step, each with L_p = ||HR - SR||_2 + lambda_pruned * ||W_P||_1 (Eq. 4 of the paper, W_P
//      the weights the pattern leaves out; pattern_masks.h). lambda_pruned is 0 by default: with
//      nested patterns every weight a narrow pattern leaves out is one a wider pattern uses, and
//      the L1 term (a sum over those weights) shrank them until the static network lost 0.24 dB
//      on the quickstart at 1e-4 (docs/results/dynamic_pruning.md). The widest pattern, the static
//      network, is itself trained. With `distill` the narrower patterns learn the widest's
//      output (detached) instead of the HR frame (in-place distillation, as slimmable networks
//      are trained): their gradients then pull the shared channels toward what the widest
//      computes rather than away from it.
//   2. fit_selector(): the dynamic pruning component (the sampler, dynamic_sampler.h) learns to
//      choose a pattern per frame from the rendering information of that frame and the one
//      before. On every training frame each pattern's PSNR loss against the widest is measured
//      on the full frame, and each pattern's cost: its MACs or its latency on this machine (the
//      latency table), as a fraction of the widest pattern's. A frame's cost of pattern k is
//      loss_dB[k] + lambda * cost[k], with lambda the smallest price for which the frames'
//      cheapest patterns meet the budget on average: easy frames (little geometry, little
//      motion) take narrow patterns, hard ones wide. The sampler is fitted to the softmax of -cost / temperature per frame
//      (cross-entropy): Eq. 4's image term plus a latency term, made a distribution so that
//      frames where patterns cost about the same do not pull hard either way.

#include <map>
#include <memory>
#include <vector>

#include "core/config.h"
#include "core/enum_names.h"
#include "models/sr_network.h"
#include "pruning/dynamic_sampler.h"
#include "pruning/pattern_masks.h"
#include "pruning/pattern_networks.h"
#include "pruning/pattern_pool.h"
#include "render_data/dataset.h"
#include "train/trainer.h"

namespace cgsr {

struct FinetuneOptions {
  double epochs = 2;             // passes over the training frames' LR pixels; 0: schedule.steps
  TrainSchedule schedule;        // batch, patch size, learning rates (steps from epochs when > 0)
  LossOptions loss;              // the image term of L_p (and the RIT gate penalty)
  double lambda_pruned = 0;      // weight of ||W_P||_1 (see above)
  int sampled_patterns = 1;      // patterns between the widest and the narrowest trained per step
  bool distill = true;           // narrower patterns learn the widest's output, not the HR frame
  FinetuneOptions();
};
config::Schema<FinetuneOptions> finetune_schema();

// Optimizer steps of `options` on `data`'s training frames at `scale`.
int finetune_steps(const FinetuneOptions& options, const Dataset& data, int scale);

// What a pattern costs when the choice is fitted. MACs make the choice reproducible; a latency
// table measured on a shared machine can differ between two runs, and the choice with it.
enum class PatternCost { Macs, Latency };
template <>
struct EnumNames<PatternCost> {
  static constexpr const char* kind = "pattern cost";
  static const std::vector<std::string>& names();  // macs, latency
};

struct SelectorOptions {
  PatternCost cost = PatternCost::Macs;
  double budget = 0.75;          // mean per-frame cost, as a fraction of the widest pattern's
  double temperature = 0.02;     // dB: cost differences below this are near-ties
  int steps = 400;               // optimizer steps (full batch of the training frames)
  double learning_rate = 1e-2;
  int frames = 0;                // training frames measured and fitted on (0 = all)
  int latency_runs = 5;          // rounds of the latency table
};
config::Schema<SelectorOptions> selector_schema();

// What fit_selector measured and chose.
struct SelectorFit {
  std::vector<int> frames;
  std::vector<std::vector<double>> loss_db;  // [frame][pattern]: PSNR below the widest pattern's
  std::vector<double> latency_ms;            // [pattern], the latency table at the frames' size
  std::vector<double> cost;                  // [pattern], fraction of the widest pattern's
  double price = 0;                          // lambda: dB per widest-pattern cost
  std::vector<int> best;                     // [frame]: the pattern of least cost
  std::vector<int> chosen;                   // [frame]: the sampler's choice after fitting
  double agreement = 0;                      // fraction of frames where chosen == best
  double mean_cost = 0;                      // of the chosen patterns, against the widest
};
nlohmann::ordered_json to_json(const SelectorFit& fit);

class DynamicPruning {
 public:
  DynamicPruning(SRNetwork network, const Dataset& data, PatternPool pool, const SamplerOptions& options);

  // The sampler input of a frame (its rendering information and that of the frame before),
  // computed once per frame.
  torch::Tensor sampler_input(int frame);
  torch::Tensor sampler_inputs(const std::vector<int>& frames);

  // Trainer hooks of the sandwich fine-tuning.
  TrainHooks hooks(const FinetuneOptions& options);

  // Step 2 on `frames` with the network as it is now.
  SelectorFit fit_selector(const std::vector<int>& frames, const SelectorOptions& options);

  // [pattern]: frames among `frames` for which the sampler chooses it.
  std::vector<int64_t> selection_counts(const std::vector<int>& frames);

  SRNetwork network() const { return network_; }
  DynamicSamplers samplers() const { return samplers_; }
  const PatternPool& pool() const { return pool_; }

 private:
  SRNetwork network_;
  const Dataset& data_;
  PatternPool pool_;
  DynamicSamplers samplers_{nullptr};
  std::vector<RenderChannel> channels_;
  std::unique_ptr<PatternMasks> masks_;
  std::map<int, torch::Tensor> inputs_;
};

}  // namespace cgsr
