#pragma once
// Training of a network on patches of a data set: Adam with cosine annealing, the CGSR loss,
// gradient-norm clipping, a guard against non-finite steps, validation on full frames, best and
// last weights, and checkpoints that resume the same schedule exactly (weights, optimizer state,
// step, RNG state, memory layout). Steps run in the memory layout measured fastest once per
// machine (or the one the schedule names; memory_layout.h measured_layout); a run is
// bit-reproducible within one layout, and the network is handed
// back in NCHW. Used by `cgsr train` and, through the search command, for search candidates.

#include <torch/optim/adam.h>

#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/json_fields.h"
#include "models/memory_layout.h"
#include "models/model_file.h"
#include "models/sr_network.h"
#include "render_data/dataset.h"
#include "train/losses.h"

namespace cgsr {

namespace distributed {
class World;
}

struct TrainSchedule {
  int steps = 2000;
  int batch_size = 16;
  int patch_size = 48;  // LR pixels; HR patches are scale x larger
  double lr_max = 1e-3;
  double lr_min = 1e-6;
  // Learning-rate factor of the rendering-information parts (RIT, HR branch, geometry head).
  // A CG-enhanced network fine-tunes a trained backbone while those parts start from scratch;
  // Adam moves a weight by about the learning rate per step, so at a fine-tuning rate a
  // zero-initialised fusion barely leaves zero in a short schedule.
  double rit_lr_scale = 1.0;
  double clip_grad_norm = 1.0;  // 0 disables clipping
  bool augment = true;          // flips and 90 degree rotations
  bool color_augment = false;   // colour permutations and gains (render_data/augment.h)
  int validate_every = 250;     // steps; 0 = only at the end
  int val_frames = 8;           // validation frames (spread over the split); 0 = all
  int checkpoint_every = 100;   // steps
  int max_nonfinite_steps = 20; // consecutive skipped steps before giving up
  MemoryLayout layout = MemoryLayout::Auto;  // activation memory layout: auto (measured once per machine), nchw or nhwc
  int prefetch = 2;             // batches built ahead on other threads (0: between steps)
  // Frames per training sequence of a recurrent network (history_out among its channels): each
  // step runs T consecutive frames in order, each fed the previous one's output, and back-propagates
  // through all of them. 0: 4 for a recurrent network, 1 otherwise.
  int sequence_length = 0;
};
config::Schema<TrainSchedule> schedule_schema();

struct ValidationScore {
  int step = 0;
  double psnr = 0, ssim = 0;
  double image_loss = 0, geometry_loss = 0;  // the joint loss terms on full frames
};

// Where the wall time of a run's steps went, in milliseconds per step (the same phases as
// bench/bench_training_step, plus waiting for the batch and the periodic work), so a slow stage
// says whether data, compute or bookkeeping is the cause.
struct StepPhases {
  double batch = 0, forward_and_loss = 0, backward_and_clip = 0, optimizer = 0, validation = 0, checkpoint = 0;
};
CGSR_JSON_FIELDS(StepPhases, batch, forward_and_loss, backward_and_clip, optimizer, validation, checkpoint)

struct TrainOutcome {
  int steps = 0;
  int skipped_steps = 0;
  double seconds = 0;
  double patches_per_second = 0;
  ValidationScore best, last;
  std::vector<ValidationScore> history;
  std::vector<double> loss_curve;  // training loss (the CGSR total) of every step, over the global batch
  bool resumed = false;
  // --resume --force: how the checkpoint's run differed from this one (train/run_identity.h).
  std::vector<std::string> resume_overrides;
  MemoryLayout layout = MemoryLayout::Nchw;  // the memory layout the steps ran in
  StepPhases phase_ms;  // over the steps this run took (a resumed run: since the resume)
};
nlohmann::ordered_json to_json(const TrainOutcome& outcome);

// Optional changes to the training step for stages that train more than the plain network
// (pruning: per-sample channel patterns chosen by dynamic pruning components, an extra penalty
// and the components' own parameters). Empty members keep the default behaviour.
struct TrainHooks {
  // Replaces network->forward_train(lr_color, info_input) in training steps and validation
  // (validation runs it in eval mode without autograd). `step` is the optimizer step.
  std::function<TrainOutput(const Batch& batch, int step)> forward;
  // Added to the CGSR loss of every training step: a differentiable scalar.
  std::function<torch::Tensor(const Batch& batch, const TrainOutput& output, int step)> extra_loss;
  // Optimized with the network's parameters, saved in checkpoints and restored with the best
  // validation weights.
  std::vector<torch::Tensor> extra_parameters;
};

class Trainer {
 public:
  Trainer(SRNetwork network, const Dataset& data, TrainSchedule schedule, LossOptions loss,
          ShrinkTargets shrink = {}, TrainHooks hooks = {});

  // Trains to the end of the schedule. With `checkpoint`, state is saved there every
  // checkpoint_every steps (atomically) and, when `resume` is set and the file exists, training
  // continues from it. Afterwards the network holds the best validation weights.
  TrainOutcome run(const std::optional<std::filesystem::path>& checkpoint = std::nullopt, bool resume = false);

  // PSNR/SSIM and loss terms on the validation frames.
  ValidationScore validate(int step);

  SRNetwork network() const { return network_; }

  // Data-parallel training over the ranks of `world`, each with the same network, data and
  // schedule: every rank draws the global batch a 1-process run draws at that step and trains on
  // its equal slice (batch_size must split evenly); losses and gradients are averaged over the
  // ranks by allreduce, so every rank takes the same optimizer step. Rank 0 alone writes the
  // checkpoint; a resume hands rank 0's checkpoint to every rank.
  void set_data_parallel(distributed::World* world) { world_ = world; }

  // A resume from a checkpoint of a different run (seed, schedule, data set: run_identity.h) is a
  // user error listing the differences; forced, it goes on and records them in the outcome.
  void set_resume_force(bool force) { resume_force_ = force; }

  // Writes the weights of the final step (the network itself holds the best ones after run()).
  void save_last_model(const std::filesystem::path& path, const Provenance& provenance) const;

 private:
  double learning_rate(int step) const;
  // The schedule's layout; for auto, measured on a training step of `batch` (memory_layout.h).
  MemoryLayout choose_layout(const Batch& batch);
  TrainOutput forward(const Batch& batch, int step);
  // Recurrent networks: the batch's sequences run in order (patch_sampler.h), each step fed the
  // previous step's output; the output and the batch of the items the loss scores (the training
  // split's frames).
  std::pair<TrainOutput, Batch> unroll(const Batch& batch);
  // Frame `frame` as validation scores it; a recurrent network runs the kValidationWarmup frames
  // of its scene before it first.
  TrainOutput forward_frame(int frame, int step);
  std::vector<torch::Tensor> tracked() const;  // the network's parameters, then the hooks' extras
  void save_checkpoint(const std::filesystem::path& path, int step, const TrainOutcome& outcome);
  std::map<std::string, std::string> identity() const;  // run_identity.h
  bool load_checkpoint(const std::filesystem::path& path, int& step, TrainOutcome& outcome);

  SRNetwork network_;
  const Dataset& data_;
  TrainSchedule schedule_;
  LossOptions loss_;
  ShrinkTargets shrink_;
  TrainHooks hooks_;
  std::vector<RenderChannel> channels_;
  std::vector<int> val_frames_;
  int sequence_ = 1;                // frames per training sequence (schedule.sequence_length resolved)
  std::vector<bool> train_frame_;   // per data set frame: in the training split
  MemoryLayout layout_ = MemoryLayout::Nchw;  // where run() keeps parameters and batches
  std::unique_ptr<torch::optim::Adam> optimizer_;
  std::vector<torch::Tensor> best_weights_, last_weights_;
  distributed::World* world_ = nullptr;
  bool resume_force_ = false;
};

}  // namespace cgsr
