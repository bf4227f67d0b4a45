#include "pruning/dynamic_pruning.h"

#include <spdlog/spdlog.h>
#include <torch/torch.h>

#include <cmath>

#include "core/error.h"
#include "render_data/patch_sampler.h"

namespace cgsr {

FinetuneOptions::FinetuneOptions() {
  schedule.lr_max = 2e-4;
  schedule.lr_min = 1e-6;
  schedule.validate_every = 0;
  loss.lambda_geometry = 0;  // L_p has no geometry term (and pruned models drop the head)
  loss.lambda_shrink = 0;
}

config::Schema<FinetuneOptions> finetune_schema() {
  config::Schema<FinetuneOptions> s;
  s.field("epochs", &FinetuneOptions::epochs,
          "passes over the training frames' pixels (paper: 2 per dynamic pruning run); 0 = schedule.steps")
      .range(0.0, 1000.0);
  s.section("schedule", &FinetuneOptions::schedule, schedule_schema(), "optimization schedule");
  s.section("loss", &FinetuneOptions::loss, loss_schema(), "image term (L2 in the paper) and RIT gate penalty");
  s.field("lambda_pruned", &FinetuneOptions::lambda_pruned,
          "weight of the L1 norm of the weights the patterns leave out (Eq. 4)")
      .at_least(0);
  s.field("soft_fraction", &FinetuneOptions::soft_fraction,
          "fraction of the steps with soft (averaged) patterns before the chosen ones")
      .range(0.0, 1.0);
  return s;
}

int finetune_steps(const FinetuneOptions& options, const Dataset& data, int scale) {
  if (options.epochs <= 0) return options.schedule.steps;
  const auto frames = data.frames(Split::Train);
  if (frames.empty()) throw Error(data.info().root.string(), "the data set has no training frames");
  const auto [lr, hr] = resolution_pair(data, scale);
  const auto& r = data.resolutions()[lr];
  const double pixels = static_cast<double>(frames.size()) * r.width * r.height;
  const double per_step = static_cast<double>(options.schedule.batch_size) * options.schedule.patch_size *
                          options.schedule.patch_size;
  return std::max(1, static_cast<int>(std::ceil(options.epochs * pixels / per_step)));
}

DynamicPruning::DynamicPruning(SRNetwork network, const Dataset& data, PatternPool pool, const SamplerOptions& options)
    : network_(std::move(network)), data_(data), pool_(std::move(pool)) {
  channels_ = options.render_channels();
  for (auto c : channels_)
    if (std::find(data.info().channels.begin(), data.info().channels.end(), c) == data.info().channels.end())
      throw Error(data.info().root.string(), "the dynamic samplers read rendering channel '" + channel_name(c) +
                                                 "', which the data set does not have");
  std::vector<int> sizes;
  for (const auto& u : pool_.units) sizes.push_back(static_cast<int>(u.patterns.size()));
  samplers_ = DynamicSamplers(options, sizes);
  masks_ = std::make_unique<PatternMasks>(*network_, pool_);
}

torch::Tensor DynamicPruning::sampler_input(int frame) {
  auto it = inputs_.find(frame);
  if (it != inputs_.end()) return it->second;
  const int scale = network_->spec().scale;
  // The samplers see depth as the network does: at inference both read the one batch.
  const DepthEncoding depth = network_->depth_encoding();
  const auto info = frame_batch(data_, frame, scale, channels_, depth).lr_info;
  torch::Tensor previous;
  if (frame > 0) previous = frame_batch(data_, frame - 1, scale, channels_, depth).lr_info;
  const auto input = cgsr::sampler_input(info, previous, channels_, samplers_->options().grid);
  return inputs_.emplace(frame, input).first->second;
}

torch::Tensor DynamicPruning::sampler_inputs(const std::vector<int>& frames) {
  std::vector<torch::Tensor> parts;
  for (int f : frames) parts.push_back(sampler_input(f));
  return torch::cat(parts, 0);
}

double DynamicPruning::warm_up(const std::vector<int>& frames, const std::vector<std::vector<int>>& assignment,
                               int steps, double learning_rate) {
  CGSR_CHECK(frames.size() == assignment.size(), "warm_up: one assignment per frame");
  const auto input = sampler_inputs(frames);
  const int64_t n = static_cast<int64_t>(frames.size()), units = static_cast<int64_t>(pool_.units.size());
  auto target = torch::empty({n, units}, torch::kLong);
  for (int64_t i = 0; i < n; ++i)
    for (int64_t u = 0; u < units; ++u) target[i][u] = assignment[i][u];
  samplers_->train();
  torch::optim::Adam optimizer(samplers_->parameters(), torch::optim::AdamOptions(learning_rate));
  for (int step = 0; step < steps; ++step) {
    const auto scores = samplers_->forward(input);  // [N, U, K]
    const auto loss = torch::nn::functional::cross_entropy(scores.reshape({n * units, -1}), target.reshape({-1}));
    optimizer.zero_grad();
    loss.backward();
    optimizer.step();
  }
  samplers_->eval();
  torch::NoGradGuard no_grad;
  const auto chosen = samplers_->forward(input).argmax(2);
  return chosen.eq(target).to(torch::kDouble).mean().item<double>();
}

std::vector<torch::Tensor> DynamicPruning::pattern_weights(const torch::Tensor& input, bool soft, bool training) {
  const auto scores = samplers_->forward(input);
  std::vector<torch::Tensor> out;
  for (size_t u = 0; u < pool_.units.size(); ++u) {
    const int64_t k = static_cast<int64_t>(pool_.units[u].patterns.size());
    const auto s = scores.select(1, static_cast<int64_t>(u)).slice(1, 0, k);
    const auto hard = torch::one_hot(s.argmax(1), k).to(s.dtype());
    if (!training) {
      out.push_back(hard);
      continue;
    }
    const auto p = torch::softmax(s, 1);
    out.push_back(soft ? p : hard + (p - p.detach()));
  }
  return out;
}

TrainHooks DynamicPruning::hooks(const FinetuneOptions& options, int total_steps) {
  TrainHooks hooks;
  const int soft_steps = static_cast<int>(std::lround(options.soft_fraction * total_steps));
  hooks.forward = [this, soft_steps](const Batch& batch, int step) {
    if (batch.frames.size() != static_cast<size_t>(batch.lr_color.size(0)))
      throw Error("dynamic pruning", "the batch does not say which frame each item comes from", ErrorKind::Internal);
    const bool training = network_->is_training();
    samplers_->train(training);
    const auto weights = pattern_weights(sampler_inputs(batch.frames), step < soft_steps, training);
    auto masks = masks_->group_masks(weights);
    TrainOutput out;
    out.image = masks_->forward(batch.lr_color, network_->info_input(batch), masks);
    if (training) last_masks_ = std::move(masks);
    return out;
  };
  const double lambda = options.lambda_pruned;
  if (lambda > 0)
    hooks.extra_loss = [this, lambda](const Batch&, const TrainOutput&, int) {
      return lambda * masks_->pruned_weight_l1(last_masks_);
    };
  hooks.extra_parameters = samplers_->parameters();
  return hooks;
}

std::vector<std::vector<int64_t>> DynamicPruning::selection_counts(const std::vector<int>& frames) {
  std::vector<std::vector<int64_t>> counts;
  for (const auto& u : pool_.units) counts.emplace_back(u.patterns.size(), 0);
  samplers_->eval();
  for (int f : frames) {
    const auto choice = samplers_->choose(sampler_input(f)).front();
    for (size_t u = 0; u < choice.size(); ++u) ++counts[u][choice[u]];
  }
  return counts;
}

}  // namespace cgsr
