#include "pipeline/verdict.h"

#include <spdlog/fmt/fmt.h>

#include <map>
#include <optional>

#include "eval/pattern_choice.h"

namespace cgsr {

config::Schema<VerdictOptions> verdict_schema() {
  config::Schema<VerdictOptions> s;
  s.field("max_search_loss_db", &VerdictOptions::max_search_loss_db,
          "test PSNR the CG-optimized network may lose against the CG-enhanced one")
      .at_least(0);
  s.field("min_enhance_gain_db", &VerdictOptions::min_enhance_gain_db,
          "test PSNR the CG-enhanced network must gain over the plain backbone trained as long (may be negative)");
  s.field("min_enhance_edge_gain_db", &VerdictOptions::min_enhance_edge_gain_db,
          "the same gain on geometry-edge pixels (the HR edge map dilated by 1 pixel)");
  s.field("max_hybrid_latency_ratio", &VerdictOptions::max_hybrid_latency_ratio,
          "mean latency per frame of the hybrid model against its static network's")
      .at_least(0);
  s.field("max_hybrid_loss_db", &VerdictOptions::max_hybrid_loss_db,
          "test PSNR the hybrid model may lose against its static network")
      .at_least(0);
  s.field("min_hybrid_gain_db", &VerdictOptions::min_hybrid_gain_db,
          "test PSNR the hybrid model must gain over the CG-optimized network it chooses around (may be negative)");
  s.field("min_hybrid_gain_over_magnitude_db", &VerdictOptions::min_hybrid_gain_over_magnitude_db,
          "test PSNR the hybrid model must gain over magnitude pruning at the same latency (may be negative)");
  s.field("min_patterns_used", &VerdictOptions::min_patterns_used, "distinct patterns chosen on the test frames")
      .at_least(0);
  s.field("max_elastic_loss_db", &VerdictOptions::max_elastic_loss_db,
          "test PSNR the elastic network's full subnet may lose against the CG-enhanced network")
      .at_least(0);
  s.field("min_search_evaluations", &VerdictOptions::min_search_evaluations, "subnets the search must score")
      .at_least(0);
  s.field("max_final_latency_fraction", &VerdictOptions::max_final_latency_fraction,
          "latency of the CG-optimized network against the backbone's")
      .at_least(0);
  s.field("max_final_loss_db", &VerdictOptions::max_final_loss_db,
          "test PSNR the CG-optimized network may lose against the backbone");
  s.field("min_gain_over_scratch_db", &VerdictOptions::min_gain_over_scratch_db,
          "PSNR the CG-optimized network must gain over its architecture trained from scratch (test and held-out)");
  s.field("min_gain_over_controls_db", &VerdictOptions::min_gain_over_controls_db,
          "PSNR the CG-optimized network must gain over every control about as fast");
  s.field("latency_tolerance", &VerdictOptions::latency_tolerance,
          "a control counts as fast as the CG-optimized network when at most this fraction slower")
      .range(0, 1);
  s.field("fail_run", &VerdictOptions::fail_run, "exit with an error when a check fails");
  return s;
}

std::vector<const EvalResult*> PipelineResults::networks() const {
  std::vector<const EvalResult*> out;
  for (const EvalResult* r : {backbone, control, cg_enhanced, elastic, cg_optimized, pruned})
    if (r) out.push_back(r);
  return out;
}

namespace {

// "a cuts X of b": strictly smaller, with the ratio in the detail.
void check_cut(Verdict& v, const std::string& stage, const std::string& what, const EvalResult& before,
               const EvalResult& after, double before_value, double after_value, const char* unit) {
  const bool passed = after_value < before_value;
  v.checks.push_back({stage + " cuts " + what, passed,
                      fmt::format("{}: {:.4g} -> {}: {:.4g} {} ({:.0f}% of it)", before.name, before_value, after.name,
                                  after_value, unit, before_value > 0 ? 100.0 * after_value / before_value : 0.0)});
}

void check_cuts(Verdict& v, const std::string& stage, const EvalResult& before, const EvalResult& after,
                double max_loss_db) {
  if (before.cost && after.cost) {
    check_cut(v, stage, "params", before, after, static_cast<double>(before.cost->params),
              static_cast<double>(after.cost->params), "params");
    check_cut(v, stage, "MACs", before, after, static_cast<double>(before.cost->macs),
              static_cast<double>(after.cost->macs), "MACs");
  } else {
    v.checks.push_back({stage + " cuts params and MACs", false, "no parameter or MAC count was evaluated"});
  }
  if (before.latency && after.latency) {
    check_cut(v, stage, "latency", before, after, before.latency->median_ms, after.latency->median_ms, "ms");
  } else {
    v.checks.push_back({stage + " cuts latency", false, "latency was not measured (eval.latency_runs is 0)"});
  }
  const double loss = before.psnr - after.psnr;
  v.checks.push_back({stage + " loses at most " + fmt::format("{:g}", max_loss_db) + " dB", loss <= max_loss_db,
                      fmt::format("{}: {:.3f} dB -> {}: {:.3f} dB ({:+.3f} dB)", before.name, before.psnr, after.name,
                                  after.psnr, -loss)});
}

// "a gains at least min_gain dB over b" on one PSNR (overall or a region of the frame); a PSNR
// that was not evaluated fails the check.
void check_gain(Verdict& v, const std::string& region, const EvalResult& a, const EvalResult& b,
                std::optional<double> a_psnr, std::optional<double> b_psnr, double min_gain) {
  const std::string claim = fmt::format("{} gains at least {:g} dB {} over {}", a.name, min_gain, region, b.name);
  if (!a_psnr || !b_psnr) {
    v.checks.push_back({claim, false, "PSNR " + region + " was not evaluated"});
    return;
  }
  v.checks.push_back({claim, *a_psnr - *b_psnr >= min_gain,
                      fmt::format("{:.3f} dB against {:.3f} dB ({:+.3f} dB)", *a_psnr, *b_psnr, *a_psnr - *b_psnr)});
}

// What the per-frame choice buys against the static network it chooses within.
void check_dynamic_pruning(Verdict& v, const EvalResult& hybrid, const EvalResult& fixed, const EvalResult* pick,
                           const EvalResult* magnitude, const VerdictOptions& options) {
  const std::string latency_claim =
      fmt::format("{} runs at most {:g}x its static network's mean latency", hybrid.name, options.max_hybrid_latency_ratio);
  if (hybrid.latency && fixed.latency) {
    const double ratio = hybrid.latency->mean_ms / fixed.latency->mean_ms;
    v.checks.push_back({latency_claim, ratio <= options.max_hybrid_latency_ratio,
                        fmt::format("{:.1f} ms against {:.1f} ms per frame ({:.2f}x; p95 {:.1f} against {:.1f} ms)",
                                    hybrid.latency->mean_ms, fixed.latency->mean_ms, ratio, hybrid.latency->p95_ms,
                                    fixed.latency->p95_ms)});
  } else {
    v.checks.push_back({latency_claim, false, "latency was not measured (eval.latency_runs is 0)"});
  }
  const double loss = fixed.psnr - hybrid.psnr;
  v.checks.push_back({fmt::format("{} loses at most {:g} dB against its static network", hybrid.name,
                                  options.max_hybrid_loss_db),
                      loss <= options.max_hybrid_loss_db,
                      fmt::format("{:.3f} dB against {:.3f} dB ({:+.3f} dB)", hybrid.psnr, fixed.psnr, -loss)});
  if (pick) {
    const double gain = hybrid.psnr - pick->psnr;
    v.checks.push_back(
        {fmt::format("{} gains at least {:g} dB over {}", hybrid.name, options.min_hybrid_gain_db, pick->name),
         gain >= options.min_hybrid_gain_db,
         fmt::format("{:.3f} dB against {:.3f} dB ({:+.3f} dB) at {:.1f} against {:.1f} ms per frame", hybrid.psnr,
                     pick->psnr, gain, hybrid.latency ? hybrid.latency->mean_ms : 0.0,
                     pick->latency ? pick->latency->mean_ms : 0.0)});
  }
  if (magnitude) {
    const double gain = hybrid.psnr - magnitude->psnr;
    v.checks.push_back(
        {fmt::format("{} gains at least {:g} dB over {}", hybrid.name, options.min_hybrid_gain_over_magnitude_db,
                     magnitude->name),
         gain >= options.min_hybrid_gain_over_magnitude_db,
         fmt::format("{:.3f} dB against {:.3f} dB ({:+.3f} dB) at {:.1f} against {:.1f} ms per frame", hybrid.psnr,
                     magnitude->psnr, gain, hybrid.latency ? hybrid.latency->mean_ms : 0.0,
                     magnitude->latency ? magnitude->latency->mean_ms : 0.0)});
  }
  const auto choices = pattern_choices(hybrid);
  const int used = choices ? static_cast<int>(choices->usage.size()) : 0;
  v.checks.push_back({fmt::format("{} uses at least {} patterns on the test frames", hybrid.name,
                                  options.min_patterns_used),
                      used >= options.min_patterns_used, choices ? usage_text(*choices) : "no frame recorded a pattern"});
}

// The final network against the backbone, its architecture from scratch and the controls.
void check_final_network(Verdict& v, const PipelineResults& r, const VerdictOptions& options) {
  const EvalResult& final_network = *r.cg_optimized;
  if (r.backbone) {
    const std::string claim = fmt::format("{} runs at most {:g} of {}'s latency", final_network.name,
                                          options.max_final_latency_fraction, r.backbone->name);
    if (final_network.latency && r.backbone->latency) {
      const double fraction = final_network.latency->median_ms / r.backbone->latency->median_ms;
      v.checks.push_back({claim, fraction <= options.max_final_latency_fraction,
                          fmt::format("{:.1f} ms against {:.1f} ms ({:.0f}%)", final_network.latency->median_ms,
                                      r.backbone->latency->median_ms, 100 * fraction)});
    } else {
      v.checks.push_back({claim, false, "latency was not measured (eval.latency_runs is 0)"});
    }
    const double loss = r.backbone->psnr - final_network.psnr;
    v.checks.push_back({fmt::format("{} loses at most {:g} dB against {}", final_network.name, options.max_final_loss_db,
                                    r.backbone->name),
                        loss <= options.max_final_loss_db,
                        fmt::format("{:.3f} dB against {:.3f} dB ({:+.3f} dB)", final_network.psnr, r.backbone->psnr,
                                    -loss)});
  }
  if (r.scratch)
    check_gain(v, "overall", final_network, *r.scratch, final_network.psnr, r.scratch->psnr,
               options.min_gain_over_scratch_db);
  for (const auto& h : r.heldout)
    if (h.cg_optimized && h.scratch)
      check_gain(v, "on held-out scene '" + h.scene + "'", *h.cg_optimized, *h.scratch, h.cg_optimized->psnr,
                 h.scratch->psnr, options.min_gain_over_scratch_db);
  for (const EvalResult* c : r.controls) {
    const std::string claim = fmt::format("{} beats {} by {:g} dB when that is as fast", final_network.name, c->name,
                                          options.min_gain_over_controls_db);
    if (!final_network.latency || !c->latency) {
      v.checks.push_back({claim, false, "latency was not measured (eval.latency_runs is 0)"});
      continue;
    }
    const double ratio = c->latency->median_ms / final_network.latency->median_ms;
    const double gain = final_network.psnr - c->psnr;
    const bool as_fast = ratio <= 1 + options.latency_tolerance;
    v.checks.push_back({claim, !as_fast || gain >= options.min_gain_over_controls_db,
                        fmt::format("{:+.3f} dB ({:.3f} against {:.3f} dB) at {:.2f}x its latency{}", gain,
                                    final_network.psnr, c->psnr, ratio, as_fast ? "" : " (slower: no threat)")});
  }
}

void check_search(Verdict& v, const std::vector<SearchRunStats>& searches, const VerdictOptions& options) {
  if (searches.empty()) return;
  const auto& s = searches.front();
  v.checks.push_back({fmt::format("the search scores at least {} subnets", options.min_search_evaluations),
                      s.evaluations >= options.min_search_evaluations,
                      fmt::format("{}: {} subnets", s.strategy, s.evaluations)});
  for (size_t i = 1; i < searches.size(); ++i) {
    const auto& b = searches[i];
    v.checks.push_back({fmt::format("{}'s front dominates {}'s at as many evaluations (hypervolume)", s.strategy,
                                    b.strategy),
                        s.hypervolume >= b.hypervolume && s.evaluations <= b.evaluations,
                        fmt::format("{:.2f} against {:.2f} dB ms over {} and {} subnets", s.hypervolume, b.hypervolume,
                                    s.evaluations, b.evaluations)});
  }
}

void check_beats_bicubic(Verdict& v, const std::vector<const EvalResult*>& networks, const EvalResult& bicubic,
                         const std::string& where) {
  for (const EvalResult* n : networks)
    v.checks.push_back({n->name + " beats bicubic" + where, n->psnr > bicubic.psnr,
                        fmt::format("{:.3f} dB against {:.3f} dB ({:+.3f} dB)", n->psnr, bicubic.psnr,
                                    n->psnr - bicubic.psnr)});
}

}  // namespace

Verdict judge_pipeline(const PipelineResults& r, const VerdictOptions& options) {
  Verdict v;
  if (r.bicubic) check_beats_bicubic(v, r.networks(), *r.bicubic, "");
  if (r.control && r.cg_enhanced) {
    check_gain(v, "overall", *r.cg_enhanced, *r.control, r.cg_enhanced->psnr, r.control->psnr,
               options.min_enhance_gain_db);
    check_gain(v, "on geometry edges", *r.cg_enhanced, *r.control, r.cg_enhanced->psnr_edge, r.control->psnr_edge,
               options.min_enhance_edge_gain_db);
  }
  if (r.cg_enhanced && r.elastic) {
    const double loss = r.cg_enhanced->psnr - r.elastic->psnr;
    v.checks.push_back({fmt::format("{} loses at most {:g} dB against {}", r.elastic->name, options.max_elastic_loss_db,
                                    r.cg_enhanced->name),
                        loss <= options.max_elastic_loss_db,
                        fmt::format("{:.3f} dB against {:.3f} dB ({:+.3f} dB)", r.elastic->psnr, r.cg_enhanced->psnr,
                                    -loss)});
  }
  if (r.cg_enhanced && r.cg_optimized) check_cuts(v, "search", *r.cg_enhanced, *r.cg_optimized, options.max_search_loss_db);
  check_search(v, r.searches, options);
  if (r.cg_optimized) check_final_network(v, r, options);
  if (r.pruned && r.pruned_static)
    check_dynamic_pruning(v, *r.pruned, *r.pruned_static, r.cg_optimized, r.magnitude, options);
  for (const auto& h : r.heldout) {
    if (h.bicubic) {
      check_beats_bicubic(v, h.networks, *h.bicubic, " on held-out scene '" + h.scene + "'");
    } else {
      v.checks.push_back({"bicubic evaluated on held-out scene '" + h.scene + "'", false, "no bicubic row there"});
    }
  }
  return v;
}

bool Verdict::passed() const { return failed() == 0; }

int Verdict::failed() const {
  int n = 0;
  for (const auto& c : checks) n += c.passed ? 0 : 1;
  return n;
}

std::string Verdict::text() const {
  std::string out;
  for (const auto& c : checks) out += fmt::format("  [{}] {}: {}\n", c.passed ? "pass" : "FAIL", c.claim, c.detail);
  out += passed() ? fmt::format("verdict: all {} checks pass\n", checks.size())
                  : fmt::format("verdict: {} of {} checks FAILED\n", failed(), checks.size());
  return out;
}

nlohmann::ordered_json Verdict::to_json() const {
  nlohmann::ordered_json j;
  j["passed"] = passed();
  j["checks"] = nlohmann::ordered_json(checks);
  return j;
}

}  // namespace cgsr
