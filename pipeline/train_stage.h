#pragma once
// The train job: what `cgsr train` runs, and the train, enhance and control stages of `cgsr run`.
// Trains a plain backbone, or turns a trained backbone into a CG-enhanced network (RIT +
// geometry head, inherited weights) and trains that; with `elastic`, trains the network as an
// elastic network whose subnets all work and measures its latency table (the elastic stage);
// with `distill`, learns a teacher's output beside the HR frame. Writes model.cgsr (best
// validation weights), last.cgsr, checkpoint.pt (for --resume) and results.json. With
// `quantization_aware`, fine-tunes through simulated INT8.

#include <nlohmann/json.hpp>

#include "core/run_dir.h"
#include "distributed/world.h"
#include "eval/calibration.h"
#include "models/arch_spec.h"
#include "pipeline/run_settings.h"
#include "train/distillation.h"
#include "train/elastic_training.h"
#include "train/losses.h"
#include "train/trainer.h"

namespace cgsr {

struct EnhanceOptions {
  bool enabled = false;  // insert the RIT (and geometry head) into the model before training
  RitSpec rit;
  GeometrySpec geometry{true, 16};
};

// Fine-tuning through simulated INT8 (train/quantization_aware.h), calibrated first.
struct QuantizationAwareOptions {
  bool enabled = false;
  CalibrationOptions calibration;
};

struct TrainOptions : RunSettings {
  std::string data;          // data set directory (required)
  std::string model = "pan"; // backbone name, spec file, or model file to start from
  int scale = 2;
  std::string name;          // display name in reports (default: derived from the spec)
  EnhanceOptions enhance;
  ElasticTrainingOptions elastic;  // train as an elastic network (train/elastic_training.h)
  DistillOptions distill;          // learn a teacher's output too (train/distillation.h)
  QuantizationAwareOptions quantization_aware;
  TrainSchedule schedule;
  LossOptions loss;
  bool resume = false;       // continue from checkpoint.pt in --out
  bool force_resume = false; // --force: resume despite differences (the command line's, not a config key)
  distributed::DistributedOptions distributed;  // data-parallel over processes (docs/distributed.md)
};

config::Schema<TrainOptions> train_schema();
// The enhance stage of `cgsr run`: a training config whose enhance block's keys (rit, geometry)
// sit at its top level, as the stage always enhances. It parses into TrainOptions, which emits
// (and is recorded) as a `cgsr train` config.
config::Schema<TrainOptions> enhance_stage_schema();
// The elastic stage of `cgsr run`: a training config whose elastic block's keys (space, sampled,
// distill, depth, width, latency) sit at its top level, as the stage always trains elastically.
config::Schema<TrainOptions> elastic_stage_schema();
nlohmann::ordered_json run_train(const TrainOptions& options, const YAML::Node& resolved, RunDir& run_dir);
// What `cgsr train --check` does beyond the schema: builds the network the run would train (the
// model, the RIT when enhancing, the elastic space when elastic; no data is read), so a spec file
// or an enhancement the run would refuse fails --check too. Returns a line saying what it built.
std::string check_train(const TrainOptions& options);
// The network that training starts from (what check_train builds): the model's weights, the RIT
// inserted when enhancing, made elastic when asked, fresh weights when elastic.from_scratch.
SRNetwork starting_network(const TrainOptions& options);

}  // namespace cgsr
