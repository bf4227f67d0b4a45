#pragma once
// The generation loop of the CG-guided architecture search (CGSR Eq. 1 and "Dataset and
// Implementation"): each generation the strategy proposes P new candidates, the evaluator trains
// and validates them, and the H = selection_ratio x P best by fitness (among survivors and new
// candidates) survive. The loop stops after `generations`, or when the strategy finds fewer than
// `min_candidates` unseen specs (the space is exhausted).
//
// The pick: the smallest candidate (by the fitness' size metric) whose validation PSNR is within
// `tolerance_db` of the parent's; ties go to the better fitness. When no candidate qualifies the
// parent itself is the pick, and the result says so. Size alone never decides.

#include <functional>
#include <string>
#include <vector>

#include "core/config.h"
#include "search/evaluator.h"
#include "search/fitness.h"
#include "search/history.h"
#include "search/search_space.h"
#include "search/strategy.h"

namespace cgsr {

struct SearchOptions {
  StrategyOptions strategy;       // {type: evolution, ...its options} or a bare name
  int population = 50;            // P: new candidates per generation
  double selection_ratio = 0.2;   // H = ratio x P survive
  int generations = 10;
  int min_candidates = 2;
  double tolerance_db = 0.05;     // pick rule: PSNR within this of the parent
  SearchSpaceOptions space;
  FitnessOptions fitness;
};
config::Schema<SearchOptions> search_schema();
// The former shape, `strategy: evolution` with a shared `operators: {...}` block, rewritten into
// the strategy block (with a deprecation warning). search_schema() applies it, and so does a
// schema that inlines the search options (config::Schema::inline_section carries upgrades).
YAML::Node move_operators_into_strategy(const YAML::Node& map, const config::Cursor& at);

struct SearchResult {
  Candidate parent;
  std::vector<Candidate> evaluated;  // every candidate of this search, in evaluation order
  Candidate pick;
  bool pick_is_parent = false;
  int generations_run = 0;
  std::string stop_reason;
};

Candidate pick_candidate(const Candidate& parent, const std::vector<Candidate>& candidates,
                         const SearchOptions& options, bool* is_parent);

// The candidates no other candidate beats on both size (params) and validation PSNR, smallest
// first: what a search found, beyond its one pick.
std::vector<Candidate> pareto_front(const std::vector<Candidate>& candidates);

SearchResult run_search(const ArchSpec& parent_spec, Evaluator& evaluator, SearchHistory& history,
                        const SearchOptions& options);

}  // namespace cgsr
