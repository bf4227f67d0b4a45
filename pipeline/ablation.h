#pragma once
// The ablation that proves or disproves that rendering information pays (issue 15; the paper's
// Fig. 6a and more). Every variant starts from one trained plain network and gets the same
// schedule and the same seeds, so the differences are the variants' own:
//
//   plain (control)       the plain network trained on for the same steps: what the extra
//                         training alone gives, the baseline every other row is compared with
//   <source>              CG-enhanced with each RIT source (lr, hr_pooled, hr_unshuffle, hr_fuse,
//                         hr_unshuffle+hr_fuse), the fusion starting at zero
//   <best> - <channel>    the best source (by validation PSNR) with one rendering channel left out
//   <best> [a+b+...]      the best source with another set of rendering channels (channel_sets):
//                         e.g. the usual G-buffers plus the BSP border channel, or that alone
//   small plain / small + <best>   the plain network at `small_width` of every width (channels
//                         inherited by importance, about small_width^2 of the parameters), without
//                         and with the best source: how much of the gap to the full network the
//                         information closes
//
// Each (variant, seed) trains in its own directory and records its evaluation there, so a killed
// ablation resumes where it stopped. The summary gives the test PSNR overall, on geometry-edge
// pixels and on the rest, mean and range over seeds, with params and MACs, as Markdown, CSV and a
// bar chart of the gains over the control.

#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/config.h"
#include "eval/evaluation.h"
#include "models/arch_spec.h"
#include "models/sr_network.h"
#include "render_data/dataset.h"
#include "train/losses.h"
#include "train/trainer.h"

namespace cgsr {

struct AblationOptions {
  std::vector<RitSource> sources = {RitSource::Lr, RitSource::HrPooled, RitSource::HrUnshuffle, RitSource::HrFuse,
                                    RitSource::HrUnshuffleHrFuse};
  RitSpec rit;               // every CG variant's RIT (channels, widths, fusion, depth encoding)
  bool leave_out = true;     // the best source with each channel left out in turn
  // The best source with each of these channel lists instead of rit.channels (render_channels.h
  // names), after the leave-out variants.
  std::vector<std::vector<std::string>> channel_sets;
  double small_width = 0.5;  // width factor of the small networks; 0 = none
  std::vector<int64_t> seeds = {1, 2};
  TrainSchedule schedule;
  LossOptions loss;
  EvalOptions eval;
};
config::Schema<AblationOptions> ablation_schema_fields();

struct AblationVariant {
  std::string name;  // "plain (control)", "hr_fuse", "hr_fuse - depth", "small + hr_fuse", ...
  std::string kind;  // control | source | leave_out | channels | small
  ArchSpec spec;
};

// One (variant, seed) run.
struct AblationRun {
  std::string variant;
  int64_t seed = 0;
  double val_psnr = 0;
  EvalResult eval;
  int64_t params = 0, macs = 0;
};

// Per variant, over seeds.
struct AblationRow {
  AblationVariant variant;
  int64_t params = 0, macs = 0;
  std::vector<int64_t> seeds;                                // the seeds of the per-seed figures
  std::vector<double> psnr, psnr_edge, psnr_rest, val_psnr;  // one per seed
};

struct AblationResult {
  std::vector<AblationRow> rows;  // control first, in the order they were trained
  std::string best_source;        // by mean validation PSNR ("" without sources)
};

// Runs every variant for every seed under `dir` (variants/<slug>/seed<k>/), skipping finished
// ones. `parent` is the trained plain network (not modified).
AblationResult run_ablation(const SRNetworkImpl& parent, const Dataset& data, const AblationOptions& options,
                            const std::filesystem::path& dir);

// The summary: Markdown table (with the gain over the control, overall and on edges), CSV,
// bar chart (PNG).
std::string ablation_markdown(const AblationResult& result);
std::string ablation_csv(const AblationResult& result);
void write_ablation_chart(const std::filesystem::path& path, const AblationResult& result);
nlohmann::ordered_json to_json(const AblationResult& result);

}  // namespace cgsr
