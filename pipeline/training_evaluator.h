#pragma once
// The search's Evaluator, implemented with the trainer: this is where the search job wires
// training into the search (which itself never sees the trainer).
//
// A candidate is evaluated in three steps:
//   1. fade: the parent trains `fade_steps` with an L1 penalty on the channels the candidate
//      will drop (the S_k of the CGSR loss), so they fade before they are cut;
//   2. cut: the candidate inherits the faded parent's most important channels (models/inherit.h)
//      and, with fewer blocks, the blocks the drop order spares (a dropped block fades whole);
//   3. train: the candidate trains a few epochs with the CGSR loss, then is validated.
// Every candidate is seeded from the global seed and its spec, so its score does not depend on
// when it is evaluated: a resumed search reaches the same result. The parent is scored as the
// candidate equal to it (all three steps), not as it stands.

#include <optional>

#include "core/config.h"
#include "models/sr_network.h"
#include "render_data/dataset.h"
#include "search/evaluator.h"
#include "train/losses.h"
#include "train/trainer.h"

namespace cgsr {

struct CandidateTraining {
  int fade_steps = 0;
  TrainSchedule schedule;
  LossOptions loss;
  bool measure_latency = false;  // for fitness.size_metric latency
};
config::Schema<CandidateTraining> candidate_training_schema();

class TrainingEvaluator : public Evaluator {
 public:
  // `drop_order`: the parent's blocks in the order shallower candidates drop them (empty: the
  // last first), as search/search_space.h uses it.
  TrainingEvaluator(SRNetwork parent, const Dataset& data, CandidateTraining options,
                    std::vector<int> drop_order = {});
  CandidateScore evaluate(const ArchSpec& spec) override;
  CandidateScore evaluate_parent() override;
  std::vector<int> block_drop_order() const override { return drop_order_; }
  // The parent blocks a candidate's blocks inherit (empty: its first ones).
  std::vector<int> parent_blocks(const ArchSpec& spec) const;

 private:
  CandidateScore score(SRNetwork network, const ValidationScore& validation, double seconds) const;
  SRNetwork parent_;
  const Dataset& data_;
  CandidateTraining options_;
  std::vector<int> drop_order_;
  int64_t lr_width_ = 0, lr_height_ = 0;  // validation frame size, for MACs and latency
};

}  // namespace cgsr
