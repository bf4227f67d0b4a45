#pragma once
// The verdict of `cgsr run`: does this run show the CGSR story? Checks, on the held-out
// evaluations of one run (all measured in the same process):
//   - every network beats bicubic PSNR;
//   - the CG-enhanced network beats the plain backbone trained on for the same steps (the
//     control: what the extra training alone gives) by `min_enhance_gain_db` overall and by
//     `min_enhance_edge_gain_db` on geometry-edge pixels, where rendering information should help;
//   - the elastic network's full subnet loses at most `max_elastic_loss_db` against the
//     CG-enhanced network it was trained from;
//   - the search cuts params, MACs and latency of the CG-enhanced network, losing at most
//     `max_search_loss_db` PSNR; it scored at least `min_search_evaluations` subnets, and
//     evolution's front has at least the hypervolume of random search's at as many evaluations;
//   - the CG-optimized network (the final network) runs at most `max_final_latency_fraction` of
//     the backbone's latency and loses at most `max_final_loss_db` against it; it beats its own
//     architecture trained from scratch as long by `min_gain_over_scratch_db`, on the test frames
//     and on every held-out scene; and no control of equal latency (a control at most
//     `latency_tolerance` slower) comes within `min_gain_over_controls_db` of it;
//   - the dynamic part pays: the hybrid model's mean latency per frame (over the test frames in
//     turn) is at most `max_hybrid_latency_ratio` of its static network's, it loses at most
//     `max_hybrid_loss_db` against the static network, gains at least `min_hybrid_gain_db` over
//     the CG-optimized network (the pick it chooses around, at about its latency) and
//     `min_hybrid_gain_over_magnitude_db` over magnitude pruning at that latency, and uses at
//     least `min_patterns_used` patterns on the test frames;
//   - on every held-out scene (one the networks never trained on), every network beats bicubic.
// Every figure in a check's detail comes from the evaluations; the thresholds are the config's.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/json_fields.h"
#include "eval/evaluation.h"

namespace cgsr {

struct VerdictOptions {
  double max_search_loss_db = 0.3;  // PSNR the CG-optimized network may lose against its parent
  double max_elastic_loss_db = 0.05;        // the elastic network's full subnet against the CG-enhanced one
  int min_search_evaluations = 1000;        // subnets the search scored
  double max_final_latency_fraction = 0.35; // CG-optimized latency against the backbone's
  double max_final_loss_db = 0.1;           // CG-optimized PSNR below the backbone's
  double min_gain_over_scratch_db = 0.1;    // against its architecture trained from scratch
  double min_gain_over_controls_db = 0.05;  // against every control about as fast
  double latency_tolerance = 0.05;          // "as fast": at most this fraction slower
  double min_enhance_gain_db = 0;       // PSNR the CG-enhanced network must gain over the control
  double min_enhance_edge_gain_db = 0;  // the same on geometry-edge pixels
  double max_hybrid_latency_ratio = 0.8;  // hybrid mean latency per frame against its static network's
  double max_hybrid_loss_db = 0.05;       // PSNR the hybrid model may lose against its static network
  double min_hybrid_gain_db = 0;          // against the CG-optimized network
  double min_hybrid_gain_over_magnitude_db = 0.05;  // against magnitude pruning at the same latency
  int min_patterns_used = 3;              // distinct patterns chosen on the test frames
  bool fail_run = true;             // a failed check makes `cgsr run` exit with an error
};
config::Schema<VerdictOptions> verdict_schema();

// A held-out scene's evaluations: bicubic and the run's networks there.
struct HeldoutScene {
  std::string scene;
  const EvalResult* bicubic = nullptr;
  std::vector<const EvalResult*> networks;
  const EvalResult* cg_optimized = nullptr;
  const EvalResult* scratch = nullptr;
};

// What a search run reports: its strategy, subnets scored and its front's hypervolume.
struct SearchRunStats {
  std::string strategy;
  int evaluations = 0;
  double hypervolume = 0;
};

// The evaluations a verdict needs, by role; a role left null is not checked.
struct PipelineResults {
  const EvalResult* bicubic = nullptr;
  const EvalResult* backbone = nullptr;      // plain backbone (e.g. PAN x2)
  const EvalResult* control = nullptr;       // the backbone trained on as long as the CG-enhanced one
  const EvalResult* cg_enhanced = nullptr;   // backbone + RIT
  const EvalResult* cg_optimized = nullptr;  // the search's pick, trained longer
  const EvalResult* pruned = nullptr;        // the hybrid model around the CG-optimized network
  const EvalResult* pruned_static = nullptr;  // the hybrid model's static network alone
  const EvalResult* magnitude = nullptr;     // magnitude pruning at the CG-optimized network's latency
  const EvalResult* elastic = nullptr;       // the elastic network's full subnet
  const EvalResult* scratch = nullptr;       // the CG-optimized architecture trained from scratch
  std::vector<const EvalResult*> controls;   // cut to the CG-optimized network's latency
  std::vector<SearchRunStats> searches;      // the search, then its baseline
  std::vector<HeldoutScene> heldout;
  std::vector<const EvalResult*> networks() const;  // every non-null learned model
};

struct VerdictCheck {
  std::string claim;   // e.g. "search cuts params"
  bool passed = false;
  std::string detail;  // the figures behind it
};
CGSR_JSON_FIELDS(VerdictCheck, claim, passed, detail)

struct Verdict {
  std::vector<VerdictCheck> checks;
  bool passed() const;
  int failed() const;
  std::string text() const;  // one line per check, then a summary line
  nlohmann::ordered_json to_json() const;
};

Verdict judge_pipeline(const PipelineResults& results, const VerdictOptions& options);

}  // namespace cgsr
