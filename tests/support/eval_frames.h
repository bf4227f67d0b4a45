#pragma once
// Evaluation options for frames `range` ("A:B") of the whole data set, without timing.

#include <string>

#include "eval/evaluation.h"

namespace cgsr::test {

inline EvalOptions all_frames(const std::string& range) {
  EvalOptions o;
  o.split = "all";
  o.frames = range;
  o.latency_runs = 0;
  return o;
}

}  // namespace cgsr::test
