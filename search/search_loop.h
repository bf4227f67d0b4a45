#pragma once
// The generation loop of the subnet search (CGSR's CG-guided NAS, run over the subnets of one
// elastic network): each generation the strategy proposes P new subnets, the evaluator scores
// them by inference, and the P best of the population and the new ones by Pareto rank on
// (quality, predicted latency), then crowding, form the next population (NSGA-II). The loop
// stops after `generations`, or when the strategy finds fewer than 2 unseen subnets.
//
// Quality is validation PSNR, or (1 - edge_weight) PSNR + edge_weight edge PSNR when the data
// has edges: how much the geometry edges, where networks lose most, weigh in the choice.
//
// A subnet that cannot be scored (a non-finite output) does what `on_failure.score` says:
// worst (it gets the worst quality and never survives), retry (evaluated once more, then worst)
// or abort (the search stops with the error).

#include <functional>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/enum_names.h"
#include "search/evaluator.h"
#include "search/history.h"
#include "search/strategy.h"

namespace cgsr {

enum class FailurePolicy { Worst, Retry, Abort };
template <>
struct EnumNames<FailurePolicy> {
  static constexpr const char* kind = "failure policy";
  static const std::vector<std::string>& names();  // worst, retry, abort
};

struct FailureOptions {
  FailurePolicy score = FailurePolicy::Worst;
};

struct SearchOptions {
  StrategyOptions strategy;   // {type: evolution, ...its options} or a bare name
  int population = 50;        // P: new subnets per generation, and the population kept
  int generations = 20;
  double edge_weight = 0;     // of edge PSNR in the quality
  FailureOptions on_failure;
};
config::Schema<SearchOptions> search_schema();

struct SearchResult {
  std::vector<Candidate> evaluated;  // every subnet of this search, in evaluation order
  std::vector<Candidate> front;      // Pareto front of quality against latency, fastest first
  int generations_run = 0;
  int failures = 0;
  std::string stop_reason;
};

// `stream` names the search's random stream ("evolution", "random"): two searches with one seed
// but other streams draw differently, a resumed one the same.
SearchResult run_search(const ElasticSpace& space, Evaluator& evaluator, SearchHistory& history,
                        const SearchOptions& options, const std::string& stream);

double candidate_quality(const SubnetScore& score, double edge_weight);

// The candidates no other beats on both predicted latency and quality, fastest first.
std::vector<Candidate> latency_front(const std::vector<Candidate>& candidates);

// The best quality on `front` within `budget_ms` of predicted latency; the fastest when none fits.
const Candidate& pick_within(const std::vector<Candidate>& front, double budget_ms);

// The pick checked by measurement. A latency table errs by several percent on a subnet, enough to
// carry the pick over its budget, so the front (fastest first, quality rising with latency) is
// bisected by measured latency among the subnets predicted within `predicted_slack` of the
// budget: the best whose `measure` is within `measured_budget`, about log2(front) timings; the
// fastest when none is. `measure` and `measured_budget` share a unit: ms, or a fraction of a
// reference network's latency timed alongside (pipeline/search_stage.cpp).
struct MeasuredPick {
  Candidate pick;
  double measured = 0;  // the pick's measure
  bool fits = false;
  std::vector<std::pair<std::string, double>> timed;  // (key, measure), in the order timed
};
MeasuredPick pick_measured(const std::vector<Candidate>& front, double predicted_budget_ms,
                           double measured_budget, const std::function<double(const Candidate&)>& measure,
                           double predicted_slack = 1.25);

// The front's hypervolume against (latency_ref, quality_ref) (core/pareto.h).
double front_hypervolume(const std::vector<Candidate>& front, double latency_ref, double quality_ref);

}  // namespace cgsr
