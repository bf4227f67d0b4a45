#pragma once
// The eval job: what `cgsr eval` runs, and the eval and heldout stages of `cgsr run`. Evaluates
// model files and classic upscalers on a data set split. Writes results.json (one entry per
// upscaler), a per-frame CSV per upscaler, summary.csv, PSNR per frame as SVG per table
// (frame_plot.h; named in results.json under "tables"), index.html (report_page.h) and, when
// asked (`images.frames`, `--save-images N`), image comparisons of the frames with the most
// geometry edges into images/.

#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/run_dir.h"
#include "eval/calibration.h"
#include "eval/evaluation.h"
#include "eval/image_comparison.h"
#include "pipeline/run_settings.h"

namespace cgsr {

struct EvalCommandOptions : RunSettings {
  std::string data;                 // data set directory (required)
  std::string scene;                // one scene of a multi-scene data set; empty: every scene
  std::vector<std::string> models;  // model files, classic upscaler names, or "classic" for all of them
  std::vector<std::string> names;   // display names, in the order of `models` (optional)
  int scale = 2;                    // scale of the classic upscalers (model files carry their own)
  EvalOptions eval;
  ComparisonOptions images = no_comparisons();   // crops and error maps of that many frames (none by default)
  std::vector<Precision> precisions = {Precision::Fp32};  // each network is evaluated in each
  CalibrationOptions calibration;                         // of int8 activations
};

config::Schema<EvalCommandOptions> eval_schema();
nlohmann::ordered_json run_eval(const EvalCommandOptions& options, RunDir* run_dir);

// Builds the upscaler for one `models` entry: a model file or a classic upscaler name.
std::unique_ptr<Upscaler> make_upscaler(const std::string& entry, const std::string& name, int scale);

// A network or hybrid upscaler in `precision` on the fused path (named "<name> int8"), INT8
// calibrated on `data` as `calibration` says; null for a classic upscaler (it has no network).
std::unique_ptr<Upscaler> upscaler_in_precision(const Upscaler& upscaler, Precision precision, const Dataset& data,
                                                const CalibrationOptions& calibration);

// The image comparisons of an eval run directory after the fact (`cgsr report --frames`): its
// config.yaml names the data set and the models, its results.json the frames evaluated.
std::vector<ComparisonImage> compare_eval_run(const std::filesystem::path& run, const ComparisonOptions& options,
                                              const std::filesystem::path& dir);

}  // namespace cgsr
