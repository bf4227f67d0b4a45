#pragma once
// ElasticOptions with the three settings the tests vary, the others at their defaults (an
// aggregate initialization that names only these warns under -Wextra).

#include "models/elastic.h"

namespace cgsr::test {

inline ElasticOptions elastic_options(int quantum, double min_width_fraction, int min_blocks) {
  ElasticOptions o;
  o.quantum = quantum;
  o.min_width_fraction = min_width_fraction;
  o.min_blocks = min_blocks;
  return o;
}

}  // namespace cgsr::test
