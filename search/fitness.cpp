#include "search/fitness.h"

#include <algorithm>

#include "core/error.h"

namespace cgsr {

config::Schema<FitnessOptions> fitness_schema() {
  config::Schema<FitnessOptions> s;
  s.field("size_metric", &FitnessOptions::size_metric, "what counts as size");
  s.field("size_weight", &FitnessOptions::size_weight, "weight of the relative size").at_least(0);
  s.field("geometry_weight", &FitnessOptions::geometry_weight, "weight of the geometry loss in the joint loss")
      .at_least(0);
  return s;
}

const std::vector<std::string>& EnumNames<SizeMetric>::names() {
  static const std::vector<std::string> names = {"params", "macs", "latency"};
  return names;
}

double size_of(const CandidateScore& score, SizeMetric metric) {
  switch (metric) {
    case SizeMetric::Params:
      return static_cast<double>(score.params);
    case SizeMetric::Macs:
      return static_cast<double>(score.macs);
    case SizeMetric::Latency:
      if (!score.latency_ms) throw Error("fitness", "size_metric latency needs measured latencies", ErrorKind::Internal);
      return *score.latency_ms;
  }
  throw Error("fitness", "unknown size metric", ErrorKind::Internal);
}

double fitness(const CandidateScore& candidate, const CandidateScore& parent, const FitnessOptions& options) {
  const double joint = candidate.image_loss + options.geometry_weight * candidate.geometry_loss;
  const double parent_joint = std::max(1e-12, parent.image_loss + options.geometry_weight * parent.geometry_loss);
  const double size = size_of(candidate, options.size_metric);
  const double parent_size = std::max(1e-12, size_of(parent, options.size_metric));
  return joint / parent_joint + options.size_weight * size / parent_size;
}

}  // namespace cgsr
