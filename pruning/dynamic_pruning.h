#pragma once
// Training the dynamic pruning components of a network on a data set (the paper's "partially
// train and fine-tune the dynamic sampler for a specific CG application"):
//
//   1. warm_up(): the samplers learn to predict, from each training frame's rendering
//      information, the pool entry its own importance ranking was merged into (cross-entropy).
//   2. hooks(): the Trainer fine-tunes network and samplers together with
//      L_p = ||HR - SR||_2 + lambda_pruned * sum ||W_P||_1 (Eq. 4). Each patch is computed with
//      its frame's pattern (pattern_masks.h): the samplers see the whole frame (as at inference)
//      and score the pool; the pattern is the softmax-weighted average of the pool's patterns for
//      the first `soft_fraction` of the steps, then the chosen (argmax) pattern with the softmax
//      gradient passed straight through, so the network trains on what inference executes.
//      Validation (eval mode) uses the chosen patterns, i.e. measures the hybrid model exactly.
//   3. selection_counts(): how often each pattern is chosen on a set of frames (static pruning
//      keeps what is chosen at least once).

#include <map>
#include <memory>
#include <vector>

#include "core/config.h"
#include "models/sr_network.h"
#include "pruning/dynamic_sampler.h"
#include "pruning/pattern_masks.h"
#include "pruning/pattern_pool.h"
#include "render_data/dataset.h"
#include "train/trainer.h"

namespace cgsr {

struct FinetuneOptions {
  double epochs = 2;             // passes over the training frames' LR pixels; 0: schedule.steps
  TrainSchedule schedule;        // batch, patch size, learning rates (steps from epochs when > 0)
  LossOptions loss;              // the image term of L_p (and the RIT gate penalty)
  double lambda_pruned = 1e-4;   // weight of sum ||W_P||_1
  double soft_fraction = 0.5;    // fraction of the steps with soft (averaged) patterns
  FinetuneOptions();
};
config::Schema<FinetuneOptions> finetune_schema();

// Optimizer steps of `options` on `data`'s training frames at `scale`.
int finetune_steps(const FinetuneOptions& options, const Dataset& data, int scale);

class DynamicPruning {
 public:
  DynamicPruning(SRNetwork network, const Dataset& data, PatternPool pool, const SamplerOptions& options);

  // The sampler input of a frame (its rendering information and that of the frame before),
  // computed once per frame.
  torch::Tensor sampler_input(int frame);
  torch::Tensor sampler_inputs(const std::vector<int>& frames);

  // Fits the samplers to `assignment[i][u]` (pool entry of frames[i] for unit u); returns the
  // fraction of (frame, unit) choices matching the assignment afterwards.
  double warm_up(const std::vector<int>& frames, const std::vector<std::vector<int>>& assignment, int steps,
                 double learning_rate);

  // Trainer hooks for the fine-tuning of `total_steps` steps.
  TrainHooks hooks(const FinetuneOptions& options, int total_steps);

  // [unit][pattern]: frames among `frames` choosing the pattern.
  std::vector<std::vector<int64_t>> selection_counts(const std::vector<int>& frames);

  SRNetwork network() const { return network_; }
  DynamicSamplers samplers() const { return samplers_; }
  const PatternPool& pool() const { return pool_; }

 private:
  // Per-unit pattern weights [N, K_u] for a batch of sampler inputs (see the header comment).
  std::vector<torch::Tensor> pattern_weights(const torch::Tensor& input, bool soft, bool training);

  SRNetwork network_;
  const Dataset& data_;
  PatternPool pool_;
  DynamicSamplers samplers_{nullptr};
  std::vector<RenderChannel> channels_;
  std::unique_ptr<PatternMasks> masks_;
  std::map<int, torch::Tensor> inputs_;
  std::map<std::string, torch::Tensor> last_masks_;  // of the last training forward, for the penalty
};

}  // namespace cgsr
