#include "pipeline/training_evaluator.h"

#include <spdlog/spdlog.h>
#include <torch/torch.h>

#include <chrono>

#include "core/hash.h"
#include "core/runtime.h"
#include "core/timing.h"
#include "models/backbone_registry.h"
#include "models/complexity.h"
#include "models/importance/block_importance.h"
#include "models/importance/channel_importance.h"
#include "models/inference.h"
#include "models/inherit.h"
#include "render_data/patch_sampler.h"
#include "search/search_space.h"

namespace cgsr {

config::Schema<CandidateTraining> candidate_training_schema() {
  config::Schema<CandidateTraining> s;
  s.field("fade_steps", &CandidateTraining::fade_steps,
          "parent steps with an L1 penalty on the channels a candidate drops (0 = cut at once)")
      .at_least(0);
  s.section("schedule", &CandidateTraining::schedule, schedule_schema(), "training of each candidate");
  s.section("loss", &CandidateTraining::loss, loss_schema(), "CGSR loss of candidate training");
  s.field("measure_latency", &CandidateTraining::measure_latency, "time every candidate (for size_metric latency)");
  return s;
}

namespace {
// A stable hash of the spec text, so a candidate's seed does not depend on evaluation order; the
// legacy basis keeps the seeds (and so the search results) of earlier runs.
uint64_t text_hash(const std::string& text) { return fnv1a64(text, kLegacyFnv1a64Basis); }
}  // namespace

TrainingEvaluator::TrainingEvaluator(SRNetwork parent, const Dataset& data, CandidateTraining options,
                                     std::vector<int> drop_order)
    : parent_(std::move(parent)), data_(data), options_(std::move(options)), drop_order_(std::move(drop_order)) {
  const auto val = data_.frames(Split::Val).empty() ? data_.frames(Split::Train) : data_.frames(Split::Val);
  const Batch b = frame_batch(data_, val.front(), parent_->spec().scale, {}, DepthEncoding::Log);
  lr_width_ = b.lr_color.size(3);
  lr_height_ = b.lr_color.size(2);
}

CandidateScore TrainingEvaluator::score(SRNetwork network, const ValidationScore& validation, double seconds) const {
  CandidateScore s;
  s.val_psnr = validation.psnr;
  s.val_ssim = validation.ssim;
  s.image_loss = validation.image_loss;
  s.geometry_loss = validation.geometry_loss;
  const Complexity cost = complexity(*network, lr_width_, lr_height_);
  s.params = cost.params;
  s.macs = cost.macs;
  s.train_seconds = seconds;
  if (options_.measure_latency) {
    const auto color = torch::rand({1, 3, lr_height_, lr_width_});
    const auto& spec = network->spec();
    torch::Tensor info;
    if (network->has_rit()) {
      const int64_t f = network->rit()->info_factor();
      info = torch::rand({1, spec.rit.info_width(), lr_height_ * f, lr_width_ * f});
    }
    s.latency_ms = measure_latency([&] { infer(*network, color, info); }, 2, 7).median_ms;
  }
  return s;
}

std::vector<int> TrainingEvaluator::parent_blocks(const ArchSpec& spec) const {
  return drop_order_.empty() ? std::vector<int>{} : kept_blocks(drop_order_, resolve_spec(spec).blocks);
}

// The parent as a candidate equal to itself: faded (with nothing to fade), copied and trained
// like any candidate. Validated untrained, it scored below candidates that had trained more, and
// the pick rule compared unlike things.
CandidateScore TrainingEvaluator::evaluate_parent() { return evaluate(parent_->spec()); }

CandidateScore TrainingEvaluator::evaluate(const ArchSpec& spec) {
  const auto started = std::chrono::steady_clock::now();
  torch::manual_seed(global_seed() ^ text_hash(SearchSpace::key(spec)));

  const auto blocks = parent_blocks(spec);
  SRNetwork base = parent_;
  if (options_.fade_steps > 0) {
    // Fade on a copy of the parent (a child equal to its parent is a bit-identical copy).
    SRNetwork faded = inherit(*parent_, parent_->spec()).network;
    // Every channel the candidate drops fades: those of the groups it narrows, and all of
    // those of the blocks it drops (groups it does not keep at all).
    ShrinkTargets shrink;
    const auto kept = inherit(*parent_, spec, {}, blocks).kept;
    for (const auto& [group, importance] : channel_importance(*parent_)) {
      const auto keep = kept.find(group);
      if (keep == kept.end() && !parse_block_group(group)) continue;  // a group the candidate keeps whole
      std::vector<int64_t> dropped;
      for (int64_t c = 0; c < importance.size(0); ++c)
        if (keep == kept.end() || std::find(keep->second.begin(), keep->second.end(), c) == keep->second.end())
          dropped.push_back(c);
      if (!dropped.empty()) shrink[group] = dropped;
    }
    TrainSchedule fade = options_.schedule;
    fade.steps = options_.fade_steps;
    fade.validate_every = 0;
    fade.val_frames = 1;
    Trainer(faded, data_, fade, options_.loss, shrink).run();
    base = faded;
  }
  SRNetwork child = inherit(*base, spec, {}, blocks).network;
  Trainer trainer(child, data_, options_.schedule, options_.loss);
  const TrainOutcome outcome = trainer.run();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return score(child, outcome.best, seconds);
}

}  // namespace cgsr
