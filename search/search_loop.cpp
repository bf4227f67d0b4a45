#include "search/search_loop.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <set>

#include "core/error.h"
#include "core/pareto.h"
#include "core/progress.h"
#include "core/runtime.h"

namespace cgsr {

const std::vector<std::string>& EnumNames<FailurePolicy>::names() {
  static const std::vector<std::string> names = {"worst", "retry", "abort"};
  return names;
}

namespace {
config::Schema<FailureOptions> failure_schema() {
  config::Schema<FailureOptions> s;
  s.field("score", &FailureOptions::score,
          "a subnet that cannot be scored: worst (never survives), retry (once more, then worst) or abort");
  return s;
}

constexpr double kFailed = -std::numeric_limits<double>::infinity();

// The population sorted best first: Pareto rank on (latency, quality), then crowding (lonelier first).
std::vector<Candidate> rank_population(std::vector<Candidate> pool, size_t keep) {
  std::vector<Candidate> alive;
  for (auto& c : pool)
    if (!c.failed) alive.push_back(std::move(c));
  std::vector<double> cost, quality;
  for (const auto& c : alive) {
    cost.push_back(c.score.latency_ms);
    quality.push_back(c.quality);
  }
  const auto rank = pareto_ranks(cost, quality);
  std::vector<double> crowd(alive.size(), 0);
  const int fronts = alive.empty() ? 0 : *std::max_element(rank.begin(), rank.end()) + 1;
  for (int r = 0; r < fronts; ++r) {
    std::vector<size_t> members;
    for (size_t i = 0; i < alive.size(); ++i)
      if (rank[i] == r) members.push_back(i);
    const auto d = crowding_distance(members, cost, quality);
    for (size_t k = 0; k < members.size(); ++k) crowd[members[k]] = d[k];
  }
  std::vector<size_t> order(alive.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return rank[a] != rank[b] ? rank[a] < rank[b] : crowd[a] > crowd[b];
  });
  std::vector<Candidate> out;
  for (size_t k = 0; k < order.size() && out.size() < keep; ++k) out.push_back(alive[order[k]]);
  return out;
}
}  // namespace

config::Schema<SearchOptions> search_schema() {
  config::Schema<SearchOptions> s;
  s.field("strategy", &SearchOptions::strategy,
          "proposes the subnets: {type: evolution, mutation_rate, crossover_rate} or random");
  s.field("population", &SearchOptions::population, "P: new subnets per generation, and the population kept")
      .range(2, 100000);
  s.field("generations", &SearchOptions::generations, "generations (P x generations evaluations)").range(1, 100000);
  s.field("edge_weight", &SearchOptions::edge_weight, "weight of geometry-edge PSNR in the quality").range(0, 1);
  s.section("on_failure", &SearchOptions::on_failure, failure_schema(), "what a subnet that cannot be scored does");
  return s;
}

double candidate_quality(const SubnetScore& score, double edge_weight) {
  if (edge_weight <= 0 || !score.psnr_edge) return score.psnr;
  return (1 - edge_weight) * score.psnr + edge_weight * *score.psnr_edge;
}

SearchResult run_search(const ElasticSpace& space, Evaluator& evaluator, SearchHistory& history,
                        const SearchOptions& options, const std::string& stream) {
  auto strategy = strategy_registry().get(options.strategy.type).make(space, options.strategy);
  SearchResult result;
  std::vector<Candidate> population;
  std::set<std::string> evaluated_keys;
  const auto seen = [&](const std::string& key) { return evaluated_keys.count(key) > 0; };
  const std::string purpose = "search-" + stream;
  for (int generation = 0; generation < options.generations; ++generation) {
    // Every strategy's first generation is drawn from one stream: with one seed, evolution and
    // random search start from the same subnets.
    auto rng = generation == 0 ? make_rng("search-first-generation") : make_rng(purpose.c_str(), generation);
    const auto proposals = strategy->propose(population, options.population, seen, rng);
    if (proposals.size() < 2) {
      result.stop_reason = "only " + std::to_string(proposals.size()) + " unseen subnet(s) left in generation " +
                           std::to_string(generation);
      break;
    }
    Progress progress(stream + " generation " + std::to_string(generation), static_cast<int64_t>(proposals.size()));
    std::vector<Candidate> fresh, news;
    for (const auto& sub : proposals) {
      Candidate c;
      c.subnet = sub;
      c.key = subnet_key(sub);
      c.generation = generation;
      if (const auto* e = history.find(c.key)) {
        c = *e;  // scored before an interruption
        c.generation = generation;
      } else {
        for (int attempt = 0;; ++attempt) {
          try {
            c.score = evaluator.evaluate(sub);
            c.failed = false;
            break;
          } catch (const Error& e) {
            if (options.on_failure.score == FailurePolicy::Abort) throw;
            c.failed = true;
            if (options.on_failure.score == FailurePolicy::Worst || attempt >= 1) {
              spdlog::warn("{}: {}; scored as the worst", c.key, e.what());
              break;
            }
            spdlog::warn("{}: {}; retrying once", c.key, e.what());
          }
        }
        fresh.push_back(c);
      }
      c.quality = c.failed ? kFailed : candidate_quality(c.score, options.edge_weight);
      if (c.failed) ++result.failures;
      evaluated_keys.insert(c.key);
      news.push_back(c);
      progress.advance();
    }
    history.append(fresh);
    progress.finish();
    result.evaluated.insert(result.evaluated.end(), news.begin(), news.end());
    std::vector<Candidate> pool = population;
    pool.insert(pool.end(), news.begin(), news.end());
    population = rank_population(std::move(pool), static_cast<size_t>(options.population));
    result.generations_run = generation + 1;
    const auto front = latency_front(result.evaluated);
    if (!front.empty())
      spdlog::info("{} generation {}: {} subnets; front of {} from {:.1f} ms / {:.3f} dB to {:.1f} ms / {:.3f} dB", stream,
                   generation, news.size(), front.size(), front.front().score.latency_ms, front.front().quality,
                   front.back().score.latency_ms, front.back().quality);
  }
  if (result.stop_reason.empty()) result.stop_reason = "generation limit " + std::to_string(options.generations);
  result.front = latency_front(result.evaluated);
  return result;
}

std::vector<Candidate> latency_front(const std::vector<Candidate>& candidates) {
  std::vector<Candidate> alive;
  for (const auto& c : candidates)
    if (!c.failed) alive.push_back(c);
  std::vector<double> cost, quality;
  for (const auto& c : alive) {
    cost.push_back(c.score.latency_ms);
    quality.push_back(c.quality);
  }
  std::vector<Candidate> front;
  std::set<std::pair<double, double>> points;  // subnets that score alike count once
  for (size_t i : pareto_front(cost, quality))
    if (points.insert({cost[i], quality[i]}).second) front.push_back(alive[i]);
  std::stable_sort(front.begin(), front.end(),
                   [](const Candidate& a, const Candidate& b) { return a.score.latency_ms < b.score.latency_ms; });
  return front;
}

const Candidate& pick_within(const std::vector<Candidate>& front, double budget_ms) {
  if (front.empty()) throw Error("search", "no subnet was scored");
  const Candidate* best = nullptr;
  for (const auto& c : front)
    if (c.score.latency_ms <= budget_ms && (!best || c.quality > best->quality)) best = &c;
  return best ? *best : front.front();
}

MeasuredPick pick_measured(const std::vector<Candidate>& front, double predicted_budget_ms,
                           double measured_budget, const std::function<double(const Candidate&)>& measure,
                           double predicted_slack) {
  if (front.empty()) throw Error("search", "no subnet was scored");
  int n = 1;
  while (n < static_cast<int>(front.size()) && front[n].score.latency_ms <= predicted_slack * predicted_budget_ms) ++n;
  MeasuredPick result;
  std::vector<double> measured(n, 0);
  int fits = -1, fails = n;  // front[..fits] measure within the budget, front[fails..] over it
  while (fails - fits > 1) {
    const int mid = (fits + fails) / 2;
    measured[mid] = measure(front[mid]);
    result.timed.emplace_back(front[mid].key, measured[mid]);
    (measured[mid] <= measured_budget ? fits : fails) = mid;
  }
  result.fits = fits >= 0;
  const int chosen = std::max(fits, 0);
  result.pick = front[chosen];
  result.measured = measured[chosen];
  return result;
}

double front_hypervolume(const std::vector<Candidate>& front, double latency_ref, double quality_ref) {
  std::vector<double> cost, quality;
  for (const auto& c : front) {
    cost.push_back(c.score.latency_ms);
    quality.push_back(c.quality);
  }
  return hypervolume(cost, quality, latency_ref, quality_ref);
}

}  // namespace cgsr
