#pragma once
// The Pareto front of points that trade a cost (smaller is better: latency, parameters) against
// a quality (larger is better: PSNR). Used by the report (PSNR against latency) and the search
// (validation PSNR against size).

#include <cstddef>
#include <vector>

namespace cgsr {

// Indices, in input order, of the points no other point dominates (no worse in both, better in
// one). `cost` and `quality` have one entry per point.
inline std::vector<size_t> pareto_front(const std::vector<double>& cost, const std::vector<double>& quality) {
  std::vector<size_t> front;
  for (size_t i = 0; i < cost.size(); ++i) {
    bool dominated = false;
    for (size_t j = 0; j < cost.size() && !dominated; ++j)
      dominated = j != i && cost[j] <= cost[i] && quality[j] >= quality[i] &&
                  (cost[j] < cost[i] || quality[j] > quality[i]);
    if (!dominated) front.push_back(i);
  }
  return front;
}

}  // namespace cgsr
