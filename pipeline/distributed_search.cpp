#include "pipeline/distributed_search.h"

#include <spdlog/spdlog.h>

#include "models/arch_spec.h"

namespace cgsr {

namespace {
// A task is the candidate's spec as YAML; its result the score as JSON (doubles round-trip).
distributed::WorkQueue::Runner candidate_runner(Evaluator& local) {
  return [&local](size_t index, const std::string& task) {
    const ArchSpec spec = spec_from_yaml(task, "distributed candidate " + std::to_string(index));
    spdlog::info("distributed: training candidate {} {}", index, spec_summary(spec));
    return nlohmann::ordered_json(local.evaluate(spec)).dump();
  };
}
}  // namespace

void DistributedEvaluator::evaluate_batch(const std::vector<ArchSpec>& specs,
                                          const std::function<void(size_t, const CandidateScore&)>& done) {
  if (specs.empty()) return;
  std::vector<std::string> tasks;
  for (const auto& spec : specs) tasks.push_back(spec_to_yaml(spec));
  queue_.run_batch(tasks, candidate_runner(local_), [&](size_t index, const std::string& result) {
    done(index, nlohmann::json::parse(result).get<CandidateScore>());
  });
}

int serve_candidates(distributed::WorkQueue& queue, Evaluator& local) { return queue.serve(candidate_runner(local)); }

}  // namespace cgsr
