#pragma once
// Fronts of points that trade a cost (smaller is better: latency, parameters) against a quality
// (larger is better: PSNR). Used by the report (PSNR against latency) and the search (NSGA-II
// selection, and the hypervolume that compares two searches' fronts).

#include <cstddef>
#include <vector>

namespace cgsr {

// Indices, in input order, of the points no other point dominates (no worse in both, better in
// one). `cost` and `quality` have one entry per point.
std::vector<size_t> pareto_front(const std::vector<double>& cost, const std::vector<double>& quality);

// Non-dominated sorting: each point's front, 0 for the Pareto front, 1 for the front of the rest,
// and so on.
std::vector<int> pareto_ranks(const std::vector<double>& cost, const std::vector<double>& quality);

// NSGA-II's crowding distance of the points `members` (one front) among themselves: the
// normalized gap between each point's neighbours along both objectives, infinite at the ends.
// Larger is lonelier, and preferred, so a front keeps its spread.
std::vector<double> crowding_distance(const std::vector<size_t>& members, const std::vector<double>& cost,
                                      const std::vector<double>& quality);

// The area the points dominate inside the box they share with the reference point: cost below
// `cost_ref`, quality above `quality_ref`. Points outside add nothing. The larger of two fronts'
// hypervolumes (with one reference) is the better front.
double hypervolume(const std::vector<double>& cost, const std::vector<double>& quality, double cost_ref,
                   double quality_ref);

}  // namespace cgsr
