#pragma once
// The controls stage of `cgsr run`: what a compressed network is measured against at equal
// latency (pruning/equal_latency_controls.h). The CG-enhanced network is narrowed by weight
// magnitude to the final network's latency, timed against it as the report times its rows
// (eval/relative_latency.h): the pruning units alone (MMP), or every layer group alike (uniform
// width). Each control is then fine-tuned like the final network: the same schedule and the same
// distillation weight, its teacher the CG-enhanced network it was cut from. Each kind is cut to
// each of `latency_factors` times the final network's latency (1: equal latency; more factors
// draw each control's PSNR-latency curve in the report); the equal-latency cut comes first, and a
// cut that is the same network as an earlier one of its kind (MMP, which keeps the residual stream
// whole, cannot run much faster than the network it is matched to) is not trained again. Writes
// <kind>.cgsr and cut_<kind>.json (the rate, kept for a resumed run) per control, <kind>_x<factor>
// for factors other than 1, and results.json (`controls`: name, file, keep rate, latency as a
// fraction of the final network's).

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/run_dir.h"
#include "pipeline/run_settings.h"
#include "pruning/equal_latency_controls.h"
#include "train/losses.h"
#include "train/trainer.h"

namespace cgsr {

struct ControlsOptions {
  std::vector<ControlKind> kinds = {ControlKind::Magnitude, ControlKind::Uniform};
  std::vector<double> latency_factors = {1.0};  // latencies cut to, as multiples of the final network's
};
config::Schema<ControlsOptions> controls_schema();

struct ControlsJob : RunSettings {
  ControlsOptions options;
  std::string enhanced;     // the CG-enhanced model file the controls are cut from
  std::string final_model;  // the network whose latency they match
  std::string data;
  TrainSchedule schedule;   // the final network's fine-tuning
  LossOptions loss;
  double distill = 1.0;
};

nlohmann::ordered_json run_controls(const ControlsJob& job, RunDir& run_dir, bool resume);

}  // namespace cgsr
