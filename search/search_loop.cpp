#include "search/search_loop.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "core/pareto.h"
#include "core/progress.h"
#include "core/runtime.h"

namespace cgsr {

// Before each strategy had its own options block, evolution's options were a shared `operators:`
// block next to `strategy: evolution`; they now sit in the strategy block.
YAML::Node move_operators_into_strategy(const YAML::Node& map, const config::Cursor& at) {
  if (!map || !map.IsMap() || !map["operators"] || !map["operators"].IsMap()) return map;
  const YAML::Node operators = map["operators"];
  YAML::Node strategy(YAML::NodeType::Map);
  const YAML::Node given = map["strategy"];
  if (given && given.IsMap())
    for (const auto& kv : given) strategy.force_insert(kv.first, kv.second);
  else
    strategy["type"] = given && given.IsScalar() ? given : YAML::Node("evolution");
  const bool evolution = strategy["type"].IsScalar() && strategy["type"].Scalar() == "evolution";
  const std::string where = at.doc ? at.doc->locate(operators) : at.child("operators").path;
  config::warn_deprecated(where, "'" + at.child("operators").path + "' is deprecated: " +
                                     (evolution ? "write its keys in the strategy block, '" + at.child("strategy").path +
                                                      ": {type: evolution, mutation_rate: ...}'"
                                                : std::string("only the evolution strategy has these options; they are ignored")));
  if (evolution)
    for (const auto& kv : operators) strategy.force_insert(kv.first, kv.second);

  YAML::Node out(YAML::NodeType::Map);
  for (const auto& kv : map) {
    const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : "";
    if (key == "operators") continue;
    out.force_insert(kv.first, key == "strategy" ? strategy : kv.second);
  }
  if (!given) out["strategy"] = strategy;
  return out;
}

config::Schema<SearchOptions> search_schema() {
  config::Schema<SearchOptions> s;
  s.field("strategy", &SearchOptions::strategy,
          "proposes the candidates: {type: evolution, initial_spread, mutation_rate, crossover_rate} or {type: random}"
          " (a bare name takes the strategy's defaults)");
  s.field("population", &SearchOptions::population, "P: new candidates per generation").range(1, 10000);
  s.field("selection_ratio", &SearchOptions::selection_ratio, "H = ratio x P candidates survive").range(0.01, 1.0);
  s.field("generations", &SearchOptions::generations, "generation limit").range(1, 10000);
  s.field("min_candidates", &SearchOptions::min_candidates, "stop when fewer unseen candidates remain").at_least(1);
  s.field("tolerance_db", &SearchOptions::tolerance_db, "pick: validation PSNR within this of the parent").at_least(0);
  s.section("space", &SearchOptions::space, search_space_schema(), "what the search may change");
  s.section("fitness", &SearchOptions::fitness, fitness_schema(), "how candidates are ranked");
  s.upgrade(move_operators_into_strategy);
  return s;
}

Candidate pick_candidate(const Candidate& parent, const std::vector<Candidate>& candidates,
                         const SearchOptions& options, bool* is_parent) {
  const Candidate* best = nullptr;
  for (const auto& c : candidates) {
    if (c.score.val_psnr < parent.score.val_psnr - options.tolerance_db) continue;
    const double size = size_of(c.score, options.fitness.size_metric);
    if (!best) {
      best = &c;
      continue;
    }
    const double best_size = size_of(best->score, options.fitness.size_metric);
    if (size < best_size || (size == best_size && c.fitness < best->fitness)) best = &c;
  }
  if (is_parent) *is_parent = best == nullptr;
  return best ? *best : parent;
}

std::vector<Candidate> pareto_front(const std::vector<Candidate>& candidates) {
  std::vector<double> params, psnr;
  for (const auto& c : candidates) {
    params.push_back(static_cast<double>(c.score.params));
    psnr.push_back(c.score.val_psnr);
  }
  std::vector<Candidate> front;
  for (size_t i : cgsr::pareto_front(params, psnr)) front.push_back(candidates[i]);
  std::stable_sort(front.begin(), front.end(),
                   [](const Candidate& a, const Candidate& b) { return a.score.params < b.score.params; });
  return front;
}

SearchResult run_search(const ArchSpec& parent_spec, Evaluator& evaluator, SearchHistory& history,
                        const SearchOptions& options) {
  const SearchSpace space(parent_spec, options.space, evaluator.block_drop_order());
  auto strategy = strategy_registry().get(options.strategy.type).make(space, options.strategy);
  SearchResult result;

  // The parent, validated once: the reference for fitness and the pick rule.
  const std::string parent_key = SearchSpace::key(space.parent());
  result.parent.spec = space.parent();
  result.parent.key = parent_key;
  result.parent.generation = -1;
  if (const auto* e = history.find(parent_key)) {
    result.parent.score = e->score;
  } else {
    result.parent.score = evaluator.evaluate_parent();
    history.append({-1, space.parent(), parent_key, result.parent.score});
  }
  result.parent.fitness = fitness(result.parent.score, result.parent.score, options.fitness);
  spdlog::info("search: parent {} validates at {:.3f} dB with {} params", spec_summary(space.parent()),
               result.parent.score.val_psnr, result.parent.score.params);

  const int survivors_wanted = std::max(1, static_cast<int>(std::lround(options.selection_ratio * options.population)));
  std::vector<Candidate> survivors;
  std::set<std::string> evaluated_keys{parent_key};
  auto seen = [&](const std::string& key) { return evaluated_keys.count(key) > 0; };

  for (int generation = 0; generation < options.generations; ++generation) {
    // Each generation draws from its own stream: a resumed search proposes the same specs.
    auto rng = make_rng("search-generation", static_cast<uint64_t>(generation));
    const auto proposals = strategy->propose(survivors, options.population, seen, rng);
    if (static_cast<int>(proposals.size()) < options.min_candidates) {
      result.stop_reason = "only " + std::to_string(proposals.size()) + " unseen candidate(s) left in generation " +
                           std::to_string(generation);
      break;
    }
    Progress progress("search generation " + std::to_string(generation), static_cast<int64_t>(proposals.size()));
    std::vector<Candidate> generation_candidates(proposals.size());
    std::vector<ArchSpec> to_evaluate;
    std::vector<size_t> slots;  // generation_candidates index of each spec in to_evaluate
    const auto report = [&](const Candidate& c) {
      progress.set_status(spec_summary(c.spec) + " " + std::to_string(c.score.val_psnr).substr(0, 6) + " dB");
      progress.advance();
    };
    for (size_t i = 0; i < proposals.size(); ++i) {
      Candidate& c = generation_candidates[i];
      c.spec = proposals[i];
      c.key = SearchSpace::key(c.spec);
      c.generation = generation;
      if (const auto* e = history.find(c.key)) {
        c.score = e->score;  // evaluated before an interruption
        report(c);
      } else {
        to_evaluate.push_back(c.spec);
        slots.push_back(i);
      }
    }
    // In proposal order, so the history reads the same however the evaluator spreads the work.
    evaluator.evaluate_batch(to_evaluate, [&](size_t k, const CandidateScore& score) {
      Candidate& c = generation_candidates[slots[k]];
      c.score = score;
      history.append({generation, c.spec, c.key, c.score});
      report(c);
    });
    for (auto& c : generation_candidates) {
      c.fitness = fitness(c.score, result.parent.score, options.fitness);
      evaluated_keys.insert(c.key);
      result.evaluated.push_back(c);
    }
    progress.finish();

    survivors.insert(survivors.end(), generation_candidates.begin(), generation_candidates.end());
    std::stable_sort(survivors.begin(), survivors.end(),
                     [](const Candidate& a, const Candidate& b) { return a.fitness < b.fitness; });
    if (static_cast<int>(survivors.size()) > survivors_wanted) survivors.resize(survivors_wanted);
    result.generations_run = generation + 1;

    bool none = false;
    const Candidate best_so_far = pick_candidate(result.parent, result.evaluated, options, &none);
    spdlog::info("generation {}: {} candidates, best fitness {:.4f} ({:.3f} dB, {} params); pick so far: {}", generation,
                 generation_candidates.size(), survivors.front().fitness, survivors.front().score.val_psnr,
                 survivors.front().score.params,
                 none ? std::string("the parent (no candidate within tolerance)")
                      : spec_summary(best_so_far.spec) + " with " + std::to_string(best_so_far.score.params) + " params");
  }
  if (result.stop_reason.empty()) result.stop_reason = "generation limit " + std::to_string(options.generations);
  result.pick = pick_candidate(result.parent, result.evaluated, options, &result.pick_is_parent);
  return result;
}

}  // namespace cgsr
