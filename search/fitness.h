#pragma once
// The fitness that ranks candidates (lower is better): the joint image + geometry validation
// loss and the model size, each relative to the parent,
//   fitness = (image + w_g geometry) / (image + w_g geometry)_parent + w_s size / size_parent
// where size is params (default), MACs or measured latency.

#include <string>

#include "core/config.h"
#include "search/evaluator.h"

namespace cgsr {

// What counts as a candidate's size: params, macs or (measured) latency.
enum class SizeMetric { Params, Macs, Latency };
template <>
struct EnumNames<SizeMetric> {
  static constexpr const char* kind = "size metric";
  static const std::vector<std::string>& names();
};

struct FitnessOptions {
  SizeMetric size_metric = SizeMetric::Params;
  double size_weight = 0.5;
  double geometry_weight = 0.1;
};
config::Schema<FitnessOptions> fitness_schema();

double fitness(const CandidateScore& candidate, const CandidateScore& parent, const FitnessOptions& options);
double size_of(const CandidateScore& score, SizeMetric metric);

}  // namespace cgsr
