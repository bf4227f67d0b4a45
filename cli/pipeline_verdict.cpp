#include "cli/pipeline_verdict.h"

#include <spdlog/fmt/fmt.h>

#include <optional>

namespace cgsr::cli {

config::Schema<VerdictOptions> verdict_schema() {
  config::Schema<VerdictOptions> s;
  s.field("max_search_loss_db", &VerdictOptions::max_search_loss_db,
          "test PSNR the CG-optimized network may lose against the CG-enhanced one")
      .at_least(0);
  s.field("max_prune_loss_db", &VerdictOptions::max_prune_loss_db,
          "test PSNR the pruned network may lose against the CG-optimized one")
      .at_least(0);
  s.field("min_enhance_gain_db", &VerdictOptions::min_enhance_gain_db,
          "test PSNR the CG-enhanced network must gain over the plain backbone trained as long (may be negative)");
  s.field("min_enhance_edge_gain_db", &VerdictOptions::min_enhance_edge_gain_db,
          "the same gain on geometry-edge pixels (the HR edge map dilated by 1 pixel)");
  s.field("fail_run", &VerdictOptions::fail_run, "exit with an error when a check fails");
  return s;
}

std::vector<const EvalResult*> PipelineResults::networks() const {
  std::vector<const EvalResult*> out;
  for (const EvalResult* r : {backbone, control, cg_enhanced, cg_optimized, pruned})
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

}  // namespace

Verdict judge_pipeline(const PipelineResults& r, const VerdictOptions& options) {
  Verdict v;
  if (r.bicubic) {
    for (const EvalResult* n : r.networks())
      v.checks.push_back({n->name + " beats bicubic", n->psnr > r.bicubic->psnr,
                          fmt::format("{:.3f} dB against {:.3f} dB ({:+.3f} dB)", n->psnr, r.bicubic->psnr,
                                      n->psnr - r.bicubic->psnr)});
  }
  if (r.control && r.cg_enhanced) {
    check_gain(v, "overall", *r.cg_enhanced, *r.control, r.cg_enhanced->psnr, r.control->psnr,
               options.min_enhance_gain_db);
    check_gain(v, "on geometry edges", *r.cg_enhanced, *r.control, r.cg_enhanced->psnr_edge, r.control->psnr_edge,
               options.min_enhance_edge_gain_db);
  }
  if (r.cg_enhanced && r.cg_optimized) check_cuts(v, "search", *r.cg_enhanced, *r.cg_optimized, options.max_search_loss_db);
  if (r.cg_optimized && r.pruned) check_cuts(v, "pruning", *r.cg_optimized, *r.pruned, options.max_prune_loss_db);
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
  j["checks"] = nlohmann::ordered_json::array();
  for (const auto& c : checks) j["checks"].push_back({{"claim", c.claim}, {"passed", c.passed}, {"detail", c.detail}});
  return j;
}

}  // namespace cgsr::cli
