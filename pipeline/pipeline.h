#pragma once
// The whole CGSR pipeline, what `cgsr run --config configs/quickstart.yaml` runs: each stage a
// job of this folder (<stage>_stage.h) in its own directory under DIR.
//
//   render   the scene (or use an existing data set)          DIR/data
//   train    the plain backbone                               DIR/train
//   enhance  backbone + RIT + geometry head (CG-enhanced)     DIR/enhance
//   control  the backbone trained on with the enhance stage's schedule and seed: what the
//            extra training alone gives, which the verdict compares CG-enhanced with   DIR/control
//   elastic  the CG-enhanced network trained once as an elastic network: every subnet of its
//            space works; its latency table measured (from_scratch: its architecture
//            from random weights)                                                DIR/elastic
//   search   evolution over the elastic network's subnets by inference (and random search at
//            as many evaluations); the pick, fine-tuned with distillation: CG-optimized  DIR/search
//   prune    hybrid pruning + magnitude baseline              DIR/prune
//   scratch  the pick's architecture trained from scratch for as many steps as the pipeline
//            gave the CG-optimized network (train, enhance, elastic, fine-tuning)   DIR/scratch
//   controls the CG-enhanced network cut by magnitude to the CG-optimized network's latency
//            (MMP, uniform width), fine-tuned alike (pipeline/controls_stage.h)   DIR/controls
//   export   ONNX + TorchScript of the final networks, verified in other runtimes   DIR/export
//   eval     classic baselines, backbone, control and CG-enhanced on the test split  DIR/eval
//   heldout  scenes not in the training data (when `heldout.scenes` names any): every model and
//            the classic baselines on each (pipeline/heldout_evaluation.h)        DIR/heldout
//   report   every model timed again side by side; table, plot  DIR/report/report.md
//            and the verdict (pipeline/verdict.h)             DIR/verdict.txt
//
// Each stage's section is the config of the matching subcommand (cgsr train, cgsr search, ...)
// without the paths, which the pipeline fills in. A stage directory records the hash of its
// resolved config and of the stages it reads (pipeline/stage_cache.h): a rerun skips finished stages,
// resumes an interrupted one, and reruns a stage whose config or inputs changed. `--from STAGE`
// reruns that stage and every later one. DIR is --out, or runs/<name>.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/config.h"
#include "eval/image_comparison.h"
#include "export/export_format.h"
#include "pipeline/controls_stage.h"
#include "pipeline/heldout_evaluation.h"
#include "eval/calibration.h"
#include "pipeline/run_settings.h"
#include "pipeline/verdict.h"

namespace cgsr {

// The scratch control: the CG-optimized network's architecture trained from random weights with
// the train stage's schedule.
struct ScratchOptions {
  bool enabled = true;
  int steps = 0;  // 0: as many as train + enhance (unless elastic.from_scratch) + elastic + the search's fine-tuning
};
config::Schema<ScratchOptions> scratch_schema();

struct PipelineOptions : RunSettings {
  std::string name = "quickstart";  // default run directory runs/<name>
  std::string scene;                // cgsr render config of the scene to render...
  std::string data;                 // ...or an existing data set (then there is no render stage)
  std::vector<std::string> baselines = {"bicubic"};  // classic upscalers in the report (bicubic is always added)
  config::Block train, enhance, elastic, search, prune;  // the subcommands' configs, paths filled in
  ScratchOptions scratch;
  ControlsOptions controls;
  std::vector<ExportFormat> export_formats = {ExportFormat::Onnx, ExportFormat::TorchScript};
  config::Block eval;                // EvalOptions shared by the eval and prune stages
  // The eval stage's networks and the CG-optimized one in each number format (fused engine);
  // int8 rows are calibrated as `calibration` says and exported as QDQ ONNX files.
  std::vector<Precision> precisions = {Precision::Fp32};
  CalibrationOptions calibration;
  HeldoutOptions heldout;            // scenes never trained on, evaluated with every model
  ComparisonOptions images;          // crops and error maps in the report
  VerdictOptions verdict;
  std::string from;                  // rerun this stage and every later one
};
config::Schema<PipelineOptions> pipeline_schema();

// The stage names, in order.
const std::vector<std::string>& pipeline_stages();

// Runs the stages in `dir`, skipping finished ones; returns the results (stages, their times).
nlohmann::ordered_json run_pipeline(const PipelineOptions& options, const YAML::Node& resolved,
                                    const std::filesystem::path& dir);
// `cgsr run --check`: parses every stage's section and every scene config the run names (a
// mistake is a cgsr::Error at its file, line and key) and returns what each stage will do in
// `dir`; runs and writes nothing.
std::string check_pipeline(const PipelineOptions& options, const std::filesystem::path& dir);

}  // namespace cgsr
