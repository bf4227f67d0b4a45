#pragma once
// Mutation and crossover of subnets (models/subnet.h) inside an elastic space: the genes are the
// width of every elastic layer group, whether each residual block is kept, and the precision
// when the space lists more than one. Results are repaired into the space (allowed widths,
// enough blocks).

#include <random>

#include "models/elastic.h"

namespace cgsr {

// Each gene changes with probability `rate`: a width moves one allowed step up or down, a block
// is dropped or restored, the precision becomes another listed one.
SubnetConfig mutate(const ElasticSpace& space, const SubnetConfig& sub, double rate, std::mt19937_64& rng);

// Each gene comes from `a` or `b` with equal probability.
SubnetConfig crossover(const ElasticSpace& space, const SubnetConfig& a, const SubnetConfig& b, std::mt19937_64& rng);

}  // namespace cgsr
