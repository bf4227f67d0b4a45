#include "train/trainer.h"

#include <spdlog/spdlog.h>
#include <torch/torch.h>

#include <cmath>
#include <sstream>

#include "core/atomic_file.h"
#include "core/enum_names.h"
#include "distributed/world.h"
#include "core/error.h"
#include "core/metrics.h"
#include "core/progress.h"
#include "core/runtime.h"
#include "core/text.h"
#include "models/arch_spec.h"
#include "render_data/history_channel.h"
#include "render_data/patch_sampler.h"
#include "train/run_identity.h"

namespace cgsr {

config::Schema<TrainSchedule> schedule_schema() {
  config::Schema<TrainSchedule> s;
  s.field("steps", &TrainSchedule::steps, "optimizer steps").range(1, 10'000'000);
  s.field("batch_size", &TrainSchedule::batch_size, "patches per step").range(1, 1024);
  s.field("patch_size", &TrainSchedule::patch_size, "LR patch side in pixels").range(4, 1024);
  s.field("lr_max", &TrainSchedule::lr_max, "learning rate at the start of the cosine schedule").range(1e-12, 100);
  s.field("lr_min", &TrainSchedule::lr_min, "learning rate at the end of the cosine schedule").range(0, 100);
  s.field("rit_lr_scale", &TrainSchedule::rit_lr_scale,
          "learning-rate factor of the rendering-information parts (RIT, HR branch, geometry head), which "
          "start from scratch when the backbone is fine-tuned")
      .range(1e-3, 1e3);
  s.field("clip_grad_norm", &TrainSchedule::clip_grad_norm, "gradient norm limit (0 = no clipping)").at_least(0);
  s.field("augment", &TrainSchedule::augment, "random flips and 90 degree rotations");
  s.field("color_augment", &TrainSchedule::color_augment,
          "random colour-channel orders and brightness gains, alike in LR and HR colour");
  s.field("validate_every", &TrainSchedule::validate_every, "steps between validations (0 = at the end)").at_least(0);
  s.field("val_frames", &TrainSchedule::val_frames, "validation frames (0 = the whole split)").at_least(0);
  s.field("checkpoint_every", &TrainSchedule::checkpoint_every, "steps between checkpoints").at_least(1);
  s.field("max_nonfinite_steps", &TrainSchedule::max_nonfinite_steps,
          "consecutive steps with a non-finite loss or gradient before training stops")
      .at_least(1);
  s.field("layout", &TrainSchedule::layout,
          "activation memory layout: auto measures both on the first batch once per machine and keeps the "
          "faster (models/memory_layout.h); nchw or nhwc pins it");
  s.field("prefetch", &TrainSchedule::prefetch,
          "batches built ahead on other threads; 0 builds each on the training thread between steps "
          "(no thread competes with the compute threads)")
      .range(0, 64);
  // Left out of the written config at its default, so stage hashes of earlier runs hold (the
  // batches are the same either way).
  s.omit_when("prefetch", [](const TrainSchedule& t) { return t.prefetch == 2; });
  s.field("sequence_length", &TrainSchedule::sequence_length,
          "frames per training sequence of a recurrent network (history_out): each step runs them in order, "
          "each fed the previous one's output; 0: 4 for a recurrent network, 1 otherwise")
      .range(0, 64);
  s.omit_when("sequence_length", [](const TrainSchedule& t) { return t.sequence_length == 0; });
  // Off, it is left out too, so stage hashes made before it existed hold.
  s.omit_when("color_augment", [](const TrainSchedule& t) { return !t.color_augment; });
  s.validate([](const TrainSchedule& t, const config::Cursor& at, const YAML::Node& node) {
    if (t.lr_min > t.lr_max) at.child("lr_min").fail(node["lr_min"] ? node["lr_min"] : node, "must not exceed lr_max");
  });
  return s;
}

nlohmann::ordered_json to_json(const TrainOutcome& o) {
  auto score = [](const ValidationScore& s) {
    nlohmann::ordered_json j;
    j["step"] = s.step;
    put_psnr(j, "psnr", s.psnr);
    j["ssim"] = s.ssim;
    j["image_loss"] = s.image_loss;
    j["geometry_loss"] = s.geometry_loss;
    return j;
  };
  nlohmann::ordered_json j;
  j["steps"] = o.steps;
  j["skipped_steps"] = o.skipped_steps;
  j["seconds"] = o.seconds;
  j["patches_per_second"] = o.patches_per_second;
  j["resumed"] = o.resumed;
  if (!o.resume_overrides.empty()) j["resume_overrides"] = o.resume_overrides;
  j["layout"] = enum_name(o.layout);
  j["phase_ms"] = o.phase_ms;
  j["best"] = score(o.best);
  j["last"] = score(o.last);
  j["history"] = nlohmann::ordered_json::array();
  for (const auto& s : o.history) j["history"].push_back(score(s));
  return j;
}

namespace {
// This rank's equal share of a global batch (data-parallel training).
Batch rank_slice(const Batch& batch, const distributed::World& world) {
  const int64_t n = batch.lr_color.size(0), per = n / world.size(), begin = world.rank() * per, end = begin + per;
  const auto cut = [&](const torch::Tensor& t) {
    return t.defined() && t.dim() > 0 && t.size(0) == n ? t.slice(0, begin, end) : t;
  };
  Batch share = batch;
  share.lr_color = cut(batch.lr_color);
  share.lr_info = cut(batch.lr_info);
  share.hr_color = cut(batch.hr_color);
  share.hr_info = cut(batch.hr_info);
  if (static_cast<int64_t>(batch.frames.size()) == n)
    share.frames.assign(batch.frames.begin() + begin, batch.frames.begin() + end);
  return share;
}

// Rank 0's checkpoint (or its absence) becomes every rank's, so all resume from the same step.
void share_checkpoint(distributed::World& world, const std::filesystem::path& path, bool resume) {
  const bool have = world.coordinator() && resume && std::filesystem::exists(path);
  const std::string payload = world.broadcast("checkpoint", have ? "1" + read_file(path) : std::string("0"));
  if (world.coordinator()) return;
  if (payload[0] == '1')
    write_file_atomic(path, payload.substr(1));
  else
    std::filesystem::remove(path);
}

// The trainable parameters: the backbone's, then the rendering-information parts' (RIT, HR
// branch, geometry head), which may learn at another rate.
struct TrainableParameters {
  std::vector<torch::Tensor> backbone, rit;
  std::vector<torch::Tensor> all() const {
    std::vector<torch::Tensor> out = backbone;
    out.insert(out.end(), rit.begin(), rit.end());
    return out;
  }
};

TrainableParameters trainable(const SRNetworkImpl& net) {
  TrainableParameters out;
  for (const auto& item : net.named_parameters()) {
    if (!item.value().requires_grad()) continue;
    const std::string& key = item.key();
    const bool rit = key.rfind("rit.", 0) == 0 || key.rfind("geometry.", 0) == 0;
    (rit ? out.rit : out.backbone).push_back(item.value());
  }
  return out;
}

std::vector<torch::Tensor> snapshot(const std::vector<torch::Tensor>& params) {
  std::vector<torch::Tensor> out;
  for (const auto& p : params) out.push_back(p.detach().clone());
  return out;
}

void restore(const std::vector<torch::Tensor>& params, const std::vector<torch::Tensor>& weights) {
  torch::NoGradGuard no_grad;
  CGSR_CHECK(params.size() == weights.size(), "weight snapshot does not match the network");
  for (size_t i = 0; i < params.size(); ++i) params[i].copy_(weights[i]);
}

torch::Tensor text_tensor(const std::string& text) {
  return torch::from_blob(const_cast<char*>(text.data()), {static_cast<int64_t>(text.size())}, torch::kUInt8).clone();
}
std::string tensor_text(const torch::Tensor& t) {
  const auto c = t.contiguous();
  return std::string(reinterpret_cast<const char*>(c.data_ptr<uint8_t>()), static_cast<size_t>(c.numel()));
}

// The batch's tensors in `layout` (the loss and metrics are layout-agnostic).
Batch in_layout(Batch b, MemoryLayout layout) {
  b.lr_color = to_layout(b.lr_color, layout);
  b.hr_color = to_layout(b.hr_color, layout);
  b.lr_info = to_layout(b.lr_info, layout);
  b.hr_info = to_layout(b.hr_info, layout);
  return b;
}

// The items `index` of a batch (whole frames' per-item fields stay with their items).
Batch batch_items(const Batch& b, const torch::Tensor& index) {
  Batch out = b;
  for (auto* t : {&out.lr_color, &out.lr_info, &out.hr_color, &out.hr_info})
    if (t->defined()) *t = t->index_select(0, index);
  out.frames.clear();
  const auto* i = index.data_ptr<int64_t>();
  for (int64_t k = 0; k < index.numel(); ++k) out.frames.push_back(b.frames.at(static_cast<size_t>(i[k])));
  out.lr_bsp_border.clear();
  out.lr_jitter.clear();
  return out;
}

// Hands the network back in NCHW however run() ends (docs/design.md: NCHW in interfaces).
struct NchwOnExit {
  torch::nn::Module& module;
  ~NchwOnExit() { set_parameter_layout(module, MemoryLayout::Nchw); }
};
}  // namespace

Trainer::Trainer(SRNetwork network, const Dataset& data, TrainSchedule schedule, LossOptions loss, ShrinkTargets shrink,
                 TrainHooks hooks)
    : network_(std::move(network)),
      data_(data),
      schedule_(schedule),
      loss_(std::move(loss)),
      shrink_(std::move(shrink)),
      hooks_(std::move(hooks)),
      channels_(network_->input_channels()) {
  const bool recurrent = reads_previous_output(channels_);
  sequence_ = schedule_.sequence_length ? schedule_.sequence_length : (recurrent ? 4 : 1);
  if (!recurrent && sequence_ > 1)
    throw Error("schedule.sequence_length", std::to_string(sequence_) + " trains on sequences, which only a recurrent "
                                            "network (history_out among rit.channels) reads; this one does not");
  if (recurrent && sequence_ < 2)
    throw Error("schedule.sequence_length", "a recurrent network (history_out) learns its state from sequences of at "
                                            "least 2 frames; got 1");
  if (recurrent && (hooks_.forward || hooks_.extra_loss))
    throw Error("train", "a recurrent network (history_out) trains without distillation, elastic or pruning hooks");
  train_frame_.assign(static_cast<size_t>(data_.info().frames), false);
  for (int f : data_.frames(Split::Train)) train_frame_[static_cast<size_t>(f)] = true;
  val_frames_ = spread_frames(data_.frames(Split::Val), schedule_.val_frames);
  if (val_frames_.empty()) val_frames_ = spread_frames(data_.frames(Split::Train), std::max(1, schedule_.val_frames));
  if (data_.frames(Split::Train).empty())
    throw Error(data_.info().root.string(), "the data set has no training frames");
}

std::vector<torch::Tensor> Trainer::tracked() const {
  auto out = network_->parameters();
  out.insert(out.end(), hooks_.extra_parameters.begin(), hooks_.extra_parameters.end());
  return out;
}

// Frames a recurrent network runs before a validation frame, from its scene's start at most.
constexpr int kValidationWarmup = 8;

TrainOutput Trainer::forward(const Batch& batch, int step) {
  if (hooks_.forward) return hooks_.forward(batch, step);
  return network_->forward_train(batch.lr_color, network_->info_input(batch));
}

std::pair<TrainOutput, Batch> Trainer::unroll(const Batch& batch) {
  const int64_t n = batch.lr_color.size(0) / sequence_;
  std::vector<torch::Tensor> images;
  torch::Tensor previous;  // none before a sequence's first frame
  for (int t = 0; t < sequence_; ++t) {
    const Batch step = batch_items(batch, torch::arange(t * n, (t + 1) * n));
    previous = network_->forward_train(step.lr_color, network_->info_input(step, previous)).image;
    images.push_back(previous);
  }
  std::vector<int64_t> scored;
  for (size_t j = 0; j < batch.frames.size(); ++j)
    if (train_frame_[static_cast<size_t>(batch.frames[j])]) scored.push_back(static_cast<int64_t>(j));
  const auto index = torch::tensor(scored);
  TrainOutput out;
  out.image = torch::cat(images).index_select(0, index);
  return {out, batch_items(batch, index)};
}

TrainOutput Trainer::forward_frame(int frame, int step) {
  const auto batch = [&](int f) {
    return in_layout(frame_batch(data_, f, network_->spec().scale, channels_, network_->depth_encoding()), layout_);
  };
  if (sequence_ == 1) return forward(batch(frame), step);
  torch::Tensor previous;
  const int first = std::max(data_.scene_of(frame).first_frame, frame - kValidationWarmup);
  for (int f = first;; ++f) {
    const Batch b = batch(f);
    auto out = network_->forward_train(b.lr_color, network_->info_input(b, previous));
    if (f == frame) return out;
    previous = out.image;
  }
}

MemoryLayout Trainer::choose_layout(const Batch& batch) {
  if (schedule_.layout != MemoryLayout::Auto) return schedule_.layout;
  // Forward and backward without hooks or optimizer step: gradients are zeroed before every
  // real step, so the measurement leaves nothing behind.
  const auto shape = batch.lr_color.sizes();
  const std::string key = "training of " + spec_summary(network_->spec()) + " on " + std::to_string(shape[0]) + "x" +
                          std::to_string(shape[3]) + "x" + std::to_string(shape[2]) + " patches";
  const MemoryLayout chosen = measured_layout(key, [&](MemoryLayout layout) {
    set_parameter_layout(*network_, layout);
    const Batch b = in_layout(batch, layout);
    const auto output = network_->forward_train(b.lr_color, network_->info_input(b));
    cgsr_loss(*network_, output, b, loss_, shrink_).total.backward();
    for (auto& p : network_->parameters())
      if (p.grad().defined()) p.mutable_grad().zero_();
  });
  return chosen;
}

double Trainer::learning_rate(int step) const {
  const double t = static_cast<double>(step) / std::max(1, schedule_.steps);
  return schedule_.lr_min + 0.5 * (schedule_.lr_max - schedule_.lr_min) * (1.0 + std::cos(M_PI * t));
}

ValidationScore Trainer::validate(int step) {
  torch::NoGradGuard no_grad;
  network_->eval();
  ValidationScore score;
  score.step = step;
  for (int frame : val_frames_) {
    const Batch b =
        in_layout(frame_batch(data_, frame, network_->spec().scale, channels_, network_->depth_encoding()), layout_);
    const auto out = forward_frame(frame, step);
    const auto image = out.image.clamp(0.0, 1.0);
    score.psnr += psnr(image, b.hr_color).item<double>();
    score.ssim += ssim(image, b.hr_color).item<double>();
    score.image_loss += reconstruction_error(out.image, b.hr_color, loss_.image_norm).item<double>();
    if (out.geometry.defined())
      score.geometry_loss +=
          reconstruction_error(out.geometry, network_->geometry_target(b), loss_.geometry_norm).item<double>();
  }
  const double n = static_cast<double>(val_frames_.size());
  score.psnr /= n;
  score.ssim /= n;
  score.image_loss /= n;
  score.geometry_loss /= n;
  network_->train();
  return score;
}

RunIdentity Trainer::identity() const {
  return run_identity(global_seed(), schedule_, data_.info(), network_->spec());
}

void Trainer::save_checkpoint(const std::filesystem::path& path, int step, const TrainOutcome& outcome) {
  torch::serialize::OutputArchive archive;
  torch::serialize::OutputArchive model, optimizer, best;
  network_->save(model);
  optimizer_->save(optimizer);
  for (size_t i = 0; i < best_weights_.size(); ++i) best.write(std::to_string(i), best_weights_[i]);
  torch::serialize::OutputArchive extra;
  for (size_t i = 0; i < hooks_.extra_parameters.size(); ++i)
    extra.write(std::to_string(i), hooks_.extra_parameters[i]);
  archive.write("extra", extra);
  archive.write("model", model);
  archive.write("optimizer", optimizer);
  archive.write("best", best);
  archive.write("step", torch::tensor(static_cast<int64_t>(step)));
  archive.write("spec", text_tensor(spec_to_yaml(network_->spec())));
  nlohmann::ordered_json state = to_json(outcome);
  state["loss_curve"] = outcome.loss_curve;
  archive.write("outcome", text_tensor(state.dump()));
  archive.write("torch_rng", at::detail::getDefaultCPUGenerator().get_state());
  archive.write("layout", text_tensor(enum_name(layout_)));
  archive.write("identity", text_tensor(nlohmann::json(identity()).dump()));
  // Serialized in memory: LibTorch's file writer throws from its destructor on a full disk, which
  // ends the process; the atomic writer reports it and keeps the last good checkpoint.
  std::ostringstream bytes;
  archive.save_to(bytes);
  write_file_atomic(path, bytes.str());
}

bool Trainer::load_checkpoint(const std::filesystem::path& path, int& step, TrainOutcome& outcome) {
  if (!std::filesystem::exists(path)) return false;
  try {
    torch::serialize::InputArchive archive, model, optimizer, best;
    archive.load_from(path.string());
    torch::Tensor spec, step_t, outcome_t, rng;
    archive.read("spec", spec);
    if (tensor_text(spec) != spec_to_yaml(network_->spec()))
      throw Error(path.string(), "the checkpoint was written for a different architecture:\n" + tensor_text(spec));
    torch::Tensor identity_t;
    if (archive.try_read("identity", identity_t)) {  // checkpoints of older versions have none
      const auto differences =
          identity_differences(nlohmann::json::parse(tensor_text(identity_t)).get<RunIdentity>(), identity());
      if (!differences.empty() && !resume_force_)
        throw Error(path.string(), "was written by a different run, so resuming would mix two:\n  " +
                                       join(differences, "\n  ") +
                                       "\nchoose another --out to start afresh, or pass --force to go on anyway");
      for (const auto& d : differences) spdlog::warn("{}: resuming despite a difference (--force): {}", path.string(), d);
      outcome.resume_overrides = differences;
    }
    archive.read("model", model);
    network_->load(model);
    if (!hooks_.extra_parameters.empty()) {
      torch::serialize::InputArchive extra;
      archive.read("extra", extra);
      torch::NoGradGuard no_grad;
      for (size_t i = 0; i < hooks_.extra_parameters.size(); ++i) {
        torch::Tensor t;
        extra.read(std::to_string(i), t);
        if (t.sizes() != hooks_.extra_parameters[i].sizes())
          throw Error(path.string(), "the checkpoint's extra training parameters do not match");
        hooks_.extra_parameters[i].copy_(t);
      }
    }
    archive.read("optimizer", optimizer);
    optimizer_->load(optimizer);
    archive.read("best", best);
    best_weights_.clear();
    for (size_t i = 0; i < tracked().size(); ++i) {
      torch::Tensor w;
      if (!best.try_read(std::to_string(i), w)) break;
      best_weights_.push_back(w);
    }
    archive.read("step", step_t);
    step = static_cast<int>(step_t.item<int64_t>());
    archive.read("outcome", outcome_t);
    const auto j = nlohmann::json::parse(tensor_text(outcome_t));
    outcome.skipped_steps = j["skipped_steps"];
    auto score = [](const nlohmann::json& s) {
      ValidationScore v;
      v.step = s["step"];
      v.psnr = s["psnr"].is_null() ? INFINITY : s["psnr"].get<double>();
      v.ssim = s["ssim"];
      v.image_loss = s["image_loss"];
      v.geometry_loss = s["geometry_loss"];
      return v;
    };
    outcome.best = score(j["best"]);
    outcome.last = score(j["last"]);
    for (const auto& s : j["history"]) outcome.history.push_back(score(s));
    if (j.contains("loss_curve"))
      for (const auto& v : j["loss_curve"]) outcome.loss_curve.push_back(v.is_null() ? NAN : v.get<double>());
    torch::Tensor layout;
    if (archive.try_read("layout", layout)) layout_ = enum_from_name<MemoryLayout>(tensor_text(layout));
    archive.read("torch_rng", rng);
    at::Generator generator = at::detail::getDefaultCPUGenerator();  // a handle to the global generator
    generator.set_state(rng);
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error(path.string(), std::string("unreadable checkpoint: ") + e.what());
  }
  if (step > schedule_.steps)
    throw Error(path.string(), "the checkpoint is at step " + std::to_string(step) + ", beyond the schedule's " +
                                   std::to_string(schedule_.steps) + " steps");
  return true;
}

TrainOutcome Trainer::run(const std::optional<std::filesystem::path>& checkpoint, bool resume) {
  const TrainableParameters groups = trainable(*network_);
  std::vector<torch::Tensor> params = groups.all(), extras;
  for (const auto& p : hooks_.extra_parameters)
    if (p.requires_grad()) extras.push_back(p);
  params.insert(params.end(), extras.begin(), extras.end());
  // One parameter group unless the rendering-information parts learn at their own rate (so that
  // the checkpoints of single-group runs still load).
  std::vector<torch::optim::OptimizerParamGroup> param_groups;
  if (schedule_.rit_lr_scale != 1.0 && !groups.rit.empty()) {
    std::vector<torch::Tensor> rest = groups.backbone;
    rest.insert(rest.end(), extras.begin(), extras.end());
    param_groups.emplace_back(rest);
    param_groups.emplace_back(groups.rit);
  } else {
    param_groups.emplace_back(params);
  }
  optimizer_ = std::make_unique<torch::optim::Adam>(param_groups, torch::optim::AdamOptions(schedule_.lr_max));
  TrainOutcome outcome;
  int step = 0;
  NchwOnExit nchw_on_exit{*network_};
  layout_ = MemoryLayout::Auto;
  if (world_) {
    if (schedule_.batch_size % world_->size() != 0)
      throw Error("schedule.batch_size", "a batch of " + std::to_string(schedule_.batch_size) +
                                             " does not split evenly over " + std::to_string(world_->size()) +
                                             " data-parallel ranks");
    if (checkpoint) share_checkpoint(*world_, *checkpoint, resume);
  }
  if (checkpoint && resume && load_checkpoint(*checkpoint, step, outcome)) {
    outcome.resumed = true;
    spdlog::info("resuming from {} at step {}/{}", checkpoint->string(), step, schedule_.steps);
  }

  PatchSamplerOptions sampling;
  sampling.scale = network_->spec().scale;
  sampling.patch_size = schedule_.patch_size;
  sampling.batch_size = schedule_.batch_size;
  sampling.split = Split::Train;
  sampling.channels = channels_;
  sampling.depth_encoding = network_->depth_encoding();
  sampling.augment = schedule_.augment;
  sampling.color_augment = schedule_.color_augment;
  sampling.prefetch = schedule_.prefetch;
  sampling.sequence_length = sequence_;
  if (world_ && sequence_ > 1)
    throw Error("train", "a recurrent network (history_out) trains in one process: its batches are sequences");
  PatchSampler sampler(data_, sampling);
  // A resumed run keeps the layout its checkpoint was written in (bit-identical steps).
  if (layout_ == MemoryLayout::Auto && (!world_ || world_->coordinator())) layout_ = choose_layout(sampler.build(step));
  if (world_) layout_ = enum_from_name<MemoryLayout>(world_->broadcast("layout", enum_name(layout_)));
  set_parameter_layout(*network_, layout_);
  if (world_) world_->broadcast_tensors(tracked());  // every rank starts from rank 0's weights
  outcome.layout = layout_;

  network_->train();
  Progress progress("train", schedule_.steps, step);
  int consecutive_bad = 0;
  using Clock = std::chrono::steady_clock;
  const auto started = Clock::now();
  const int first_step = step;
  // Seconds per phase, summed over the steps; `lap` adds the time since the previous lap.
  StepPhases spent;
  auto lap_start = Clock::now();
  const auto lap = [&](double& phase) {
    const auto now = Clock::now();
    phase += std::chrono::duration<double>(now - lap_start).count();
    lap_start = now;
  };
  while (step < schedule_.steps) {
    const double lr = learning_rate(step);
    for (size_t g = 0; g < optimizer_->param_groups().size(); ++g)
      static_cast<torch::optim::AdamOptions&>(optimizer_->param_groups()[g].options())
          .lr(g == 1 ? lr * schedule_.rit_lr_scale : lr);

    // Batches are a function of the step, so a resumed run sees the same data.
    lap_start = Clock::now();
    Batch batch = in_layout(world_ ? rank_slice(sampler.batch(step), *world_) : sampler.batch(step), layout_);
    lap(spent.batch);
    TrainOutput output;
    if (sequence_ > 1)
      std::tie(output, batch) = unroll(batch);
    else
      output = forward(batch, step);
    LossTerms terms = cgsr_loss(*network_, output, batch, loss_, shrink_);
    if (hooks_.extra_loss) terms.total = terms.total + hooks_.extra_loss(batch, output, step);
    optimizer_->zero_grad();
    double loss = terms.total.item<double>(), image_loss = terms.image;
    bool finite = std::isfinite(loss);
    if (world_) {
      // Decided together: a rank that skipped its backward alone would leave the others waiting.
      const auto stats = torch::tensor({finite ? loss : 0.0, finite ? image_loss : 0.0, finite ? 0.0 : 1.0},
                                       torch::kFloat64);
      world_->allreduce_mean({stats});
      finite = stats[2].item<double>() == 0;
      loss = finite ? stats[0].item<double>() : NAN;
      image_loss = stats[1].item<double>();
    }
    outcome.loss_curve.push_back(loss);
    lap(spent.forward_and_loss);
    if (finite) {
      terms.total.backward();
      if (world_) {
        std::vector<torch::Tensor> gradients;
        for (const auto& p : params)
          if (p.grad().defined()) gradients.push_back(p.grad());
        world_->allreduce_mean(gradients);
      }
      const double limit = schedule_.clip_grad_norm > 0 ? schedule_.clip_grad_norm : INFINITY;
      finite = std::isfinite(torch::nn::utils::clip_grad_norm_(params, limit));
    }
    lap(spent.backward_and_clip);
    if (finite) {
      optimizer_->step();
      consecutive_bad = 0;
    } else {
      optimizer_->zero_grad();
      ++outcome.skipped_steps;
      spdlog::warn("step {}: non-finite loss or gradient (lr {:.3g}); step skipped", step, lr);
      if (++consecutive_bad >= schedule_.max_nonfinite_steps)
        throw Error("train", std::to_string(consecutive_bad) + " consecutive steps with a non-finite loss or gradient "
                             "at step " + std::to_string(step) + " (learning rate " + std::to_string(lr) +
                             "); lower schedule.lr_max");
    }
    lap(spent.optimizer);
    ++step;
    progress.set_status("loss " + std::to_string(image_loss).substr(0, 8) + " lr " + std::to_string(lr).substr(0, 8));
    progress.advance();

    const bool last = step == schedule_.steps;
    if ((schedule_.validate_every > 0 && step % schedule_.validate_every == 0) || last) {
      const ValidationScore score = validate(step);
      outcome.history.push_back(score);
      outcome.last = score;
      if (best_weights_.empty() || score.psnr > outcome.best.psnr) {
        outcome.best = score;
        best_weights_ = snapshot(tracked());
      }
      spdlog::info("step {}: validation PSNR {:.3f} dB, SSIM {:.4f} (best {:.3f} at step {})", step, score.psnr,
                   score.ssim, outcome.best.psnr, outcome.best.step);
      lap(spent.validation);
    }
    if (checkpoint && (!world_ || world_->coordinator()) && (step % schedule_.checkpoint_every == 0 || last)) {
      save_checkpoint(*checkpoint, step, outcome);
      lap(spent.checkpoint);
    }
  }
  progress.finish();
  // A run can end before max_nonfinite_steps skipped steps in a row with weights whose outputs
  // overflow (learning rate far too high): do not hand those back as its result.
  if (!std::isfinite(outcome.best.image_loss) || !std::isfinite(outcome.best.geometry_loss))
    throw Error("train", "the best validation (step " + std::to_string(outcome.best.step) +
                             ") has a non-finite loss (image " + std::to_string(outcome.best.image_loss) +
                             ", geometry " + std::to_string(outcome.best.geometry_loss) + ") after " +
                             std::to_string(outcome.skipped_steps) + " skipped non-finite steps; lower schedule.lr_max");
  outcome.steps = step;
  const double ms_per_step = step > first_step ? 1e3 / (step - first_step) : 0;
  for (double StepPhases::*phase : {&StepPhases::batch, &StepPhases::forward_and_loss, &StepPhases::backward_and_clip,
                                    &StepPhases::optimizer, &StepPhases::validation, &StepPhases::checkpoint})
    outcome.phase_ms.*phase = spent.*phase * ms_per_step;
  outcome.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  outcome.patches_per_second =
      outcome.seconds > 0 ? (step - first_step) * static_cast<double>(schedule_.batch_size) / outcome.seconds : 0;
  last_weights_ = snapshot(tracked());
  if (!best_weights_.empty()) restore(tracked(), best_weights_);
  network_->eval();
  return outcome;
}

void Trainer::save_last_model(const std::filesystem::path& path, const Provenance& provenance) const {
  CGSR_CHECK(!last_weights_.empty(), "save_last_model() before run()");
  const auto best = snapshot(tracked());
  restore(tracked(), last_weights_);
  save_model(path, *network_, provenance);
  restore(tracked(), best);
}

}  // namespace cgsr
