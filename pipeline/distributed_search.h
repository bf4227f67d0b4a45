#pragma once
// The search over several processes: rank 0 runs the search loop (history, resume, the pick)
// with a DistributedEvaluator, which hands each generation's new candidates to a WorkQueue
// (distributed/work_queue.h); every rank, rank 0 included, claims candidates and trains them with
// its own TrainingEvaluator. A candidate's score depends only on its spec (it is seeded from
// it), so the history and the pick are those of a 1-process run with the same seed, threads and
// fixed memory layout. A rank that dies mid-candidate is noticed by its missing heartbeat and its
// candidate is trained again by another rank.

#include "distributed/work_queue.h"
#include "search/evaluator.h"

namespace cgsr {

class DistributedEvaluator : public Evaluator {
 public:
  DistributedEvaluator(Evaluator& local, distributed::WorkQueue& queue) : local_(local), queue_(queue) {}
  CandidateScore evaluate(const ArchSpec& spec) override { return local_.evaluate(spec); }
  CandidateScore evaluate_parent() override { return local_.evaluate_parent(); }
  std::vector<int> block_drop_order() const override { return local_.block_drop_order(); }
  void evaluate_batch(const std::vector<ArchSpec>& specs,
                      const std::function<void(size_t, const CandidateScore&)>& done) override;

 private:
  Evaluator& local_;
  distributed::WorkQueue& queue_;
};

// Ranks > 0: trains the candidates rank 0 publishes until the search ends; returns how many.
int serve_candidates(distributed::WorkQueue& queue, Evaluator& local);

}  // namespace cgsr
