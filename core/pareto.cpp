#include "core/pareto.h"

#include <algorithm>
#include <limits>
#include <numeric>

namespace cgsr {

namespace {
bool dominates(size_t j, size_t i, const std::vector<double>& cost, const std::vector<double>& quality) {
  return cost[j] <= cost[i] && quality[j] >= quality[i] && (cost[j] < cost[i] || quality[j] > quality[i]);
}
}  // namespace

std::vector<size_t> pareto_front(const std::vector<double>& cost, const std::vector<double>& quality) {
  std::vector<size_t> front;
  for (size_t i = 0; i < cost.size(); ++i) {
    bool dominated = false;
    for (size_t j = 0; j < cost.size() && !dominated; ++j) dominated = j != i && dominates(j, i, cost, quality);
    if (!dominated) front.push_back(i);
  }
  return front;
}

std::vector<int> pareto_ranks(const std::vector<double>& cost, const std::vector<double>& quality) {
  const size_t n = cost.size();
  std::vector<int> rank(n, -1);
  std::vector<int> dominated_by(n, 0);
  std::vector<std::vector<size_t>> dominates_list(n);
  for (size_t i = 0; i < n; ++i)
    for (size_t j = 0; j < n; ++j)
      if (i != j && dominates(i, j, cost, quality)) {
        dominates_list[i].push_back(j);
        ++dominated_by[j];
      }
  std::vector<size_t> current;
  for (size_t i = 0; i < n; ++i)
    if (dominated_by[i] == 0) current.push_back(i);
  for (int r = 0; !current.empty(); ++r) {
    std::vector<size_t> next;
    for (size_t i : current) {
      rank[i] = r;
      for (size_t j : dominates_list[i])
        if (--dominated_by[j] == 0) next.push_back(j);
    }
    current = std::move(next);
  }
  return rank;
}

std::vector<double> crowding_distance(const std::vector<size_t>& members, const std::vector<double>& cost,
                                      const std::vector<double>& quality) {
  const size_t n = members.size();
  std::vector<double> distance(n, 0.0);
  if (n <= 2) return std::vector<double>(n, std::numeric_limits<double>::infinity());
  for (const auto* objective : {&cost, &quality}) {
    const auto& v = *objective;
    std::vector<size_t> order(n);
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return v[members[a]] < v[members[b]]; });
    const double span = v[members[order.back()]] - v[members[order.front()]];
    distance[order.front()] = distance[order.back()] = std::numeric_limits<double>::infinity();
    if (span <= 0) continue;
    for (size_t k = 1; k + 1 < n; ++k)
      distance[order[k]] += (v[members[order[k + 1]]] - v[members[order[k - 1]]]) / span;
  }
  return distance;
}

double hypervolume(const std::vector<double>& cost, const std::vector<double>& quality, double cost_ref,
                   double quality_ref) {
  std::vector<size_t> inside;
  for (size_t i = 0; i < cost.size(); ++i)
    if (cost[i] < cost_ref && quality[i] > quality_ref) inside.push_back(i);
  // Sweep by increasing cost: each point adds the strip up to the next cost (or the reference)
  // at the best quality reached so far.
  std::sort(inside.begin(), inside.end(), [&](size_t a, size_t b) { return cost[a] < cost[b]; });
  double area = 0, best = quality_ref;
  for (size_t k = 0; k < inside.size(); ++k) {
    best = std::max(best, quality[inside[k]]);
    const double next = k + 1 < inside.size() ? cost[inside[k + 1]] : cost_ref;
    area += (next - cost[inside[k]]) * (best - quality_ref);
  }
  return area;
}

}  // namespace cgsr
