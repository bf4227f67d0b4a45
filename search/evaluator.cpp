#include "search/evaluator.h"

namespace cgsr {

void Evaluator::evaluate_batch(const std::vector<ArchSpec>& specs,
                               const std::function<void(size_t, const CandidateScore&)>& done) {
  for (size_t i = 0; i < specs.size(); ++i) done(i, evaluate(specs[i]));
}

}  // namespace cgsr
