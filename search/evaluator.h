#pragma once
// What a search strategy knows about a candidate: its spec in, scores out. The search command
// implements this with the trainer (warm start, a few epochs, validation); the search itself
// never sees training, so candidates could as well be evaluated on other machines.

#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "core/json_fields.h"
#include "models/arch_spec.h"

namespace cgsr {

struct CandidateScore {
  double val_psnr = 0, val_ssim = 0;
  double image_loss = 0, geometry_loss = 0;  // validation loss terms (the joint objective)
  int64_t params = 0, macs = 0;              // inference network, at the evaluation LR size
  std::optional<double> latency_ms;          // measured when the fitness asks for it
  double train_seconds = 0;
};

// A search history line's and a distributed reply's "score"; latency_ms is null when not measured.
CGSR_JSON_FIELDS(CandidateScore, val_psnr, val_ssim, image_loss, geometry_loss, params, macs, latency_ms, train_seconds)

class Evaluator {
 public:
  virtual ~Evaluator() = default;
  // Trains (warm start from the parent) and validates one candidate. Must be deterministic for
  // a given spec, so that a resumed search reaches the same result.
  virtual CandidateScore evaluate(const ArchSpec& spec) = 0;
  // The parent itself, given exactly a candidate's treatment (same training, same validation),
  // so the pick rule compares like with like.
  virtual CandidateScore evaluate_parent() = 0;
  // The parent's blocks, least important first (models/importance/block_importance.h): the order in which
  // shallower candidates drop them. Empty: the last block first.
  virtual std::vector<int> block_drop_order() const { return {}; }
  // A generation's new candidates: reports each score as done(index, score), in index order
  // (the order the history records). By default one after another in this process; a
  // distributed evaluator spreads them over processes (pipeline/distributed_search.h).
  virtual void evaluate_batch(const std::vector<ArchSpec>& specs,
                              const std::function<void(size_t index, const CandidateScore& score)>& done);
};

}  // namespace cgsr
