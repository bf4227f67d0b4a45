#include "train/elastic_training.h"

#include <torch/torch.h>

#include <algorithm>
#include <random>

#include "models/graph.h"
#include "models/subnet.h"

namespace cgsr {

namespace {
config::Schema<ShrinkPhase> shrink_phase_schema() {
  config::Schema<ShrinkPhase> s;
  s.field("start", &ShrinkPhase::start, "fraction of the steps where shrinking begins").range(0, 1);
  s.field("ramp", &ShrinkPhase::ramp, "fraction of the steps over which the whole range opens").range(0, 1);
  return s;
}

double opened(const ShrinkPhase& phase, double progress) {
  if (progress < phase.start) return 0;
  if (phase.ramp <= 0) return 1;
  return std::min(1.0, (progress - phase.start) / phase.ramp);
}
}  // namespace

config::Schema<ElasticTrainingOptions> elastic_training_schema(bool with_enabled) {
  config::Schema<ElasticTrainingOptions> s;
  if (with_enabled)
    s.field("enabled", &ElasticTrainingOptions::enabled,
            "train the network as an elastic network (sorted channels, sandwich rule)");
  s.field("from_scratch", &ElasticTrainingOptions::from_scratch,
          "start from random weights of the model's architecture, not its trained ones");
  // Written only when set, so stage hashes from before the option read the same.
  s.omit_when("from_scratch", [](const ElasticTrainingOptions& o) { return !o.from_scratch; });
  s.section("space", &ElasticTrainingOptions::space, elastic_options_schema(), "the subnets the network must hold");
  s.field("sampled", &ElasticTrainingOptions::sampled, "random subnets per step besides the full one and the smallest")
      .range(0, 16);
  s.field("distill", &ElasticTrainingOptions::distill,
          "weight of the full network's output in a subnet's target (the rest: the HR frame)")
      .range(0, 1);
  s.section("depth", &ElasticTrainingOptions::depth, shrink_phase_schema(), "when subnets start skipping blocks");
  s.section("width", &ElasticTrainingOptions::width, shrink_phase_schema(), "when subnets start narrowing");
  s.section("latency", &ElasticTrainingOptions::latency, latency_table_schema(),
            "the latency table measured after training at the data set's LR size, stored with the model");
  return s;
}

ShrinkLimits shrink_limits(const ElasticTrainingOptions& options, int step, int steps) {
  const double progress = steps > 0 ? static_cast<double>(step) / steps : 1.0;
  return {opened(options.width, progress), opened(options.depth, progress)};
}

std::vector<SubnetConfig> step_subnets(const ElasticSpace& space, const ElasticTrainingOptions& options, int step,
                                       int steps, uint64_t seed) {
  const ShrinkLimits limits = shrink_limits(options, step, steps);
  if (limits.width <= 0 && limits.depth <= 0) return {};  // only the full network so far
  std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ull + static_cast<uint64_t>(step));
  std::vector<SubnetConfig> subnets = {space.smallest(limits)};
  for (int i = 0; i < options.sampled; ++i) subnets.push_back(space.sample(rng, limits));
  return subnets;
}

TrainHooks elastic_training_hooks(SRNetwork network, const ElasticSpace& space, const ElasticTrainingOptions& options,
                                  LossOptions loss, int steps, uint64_t seed) {
  return subnet_training_hooks(
      network, [space, options, steps, seed](int step) { return step_subnets(space, options, step, steps, seed); },
      options.distill, loss);
}

TrainHooks subnet_training_hooks(SRNetwork network, std::function<std::vector<SubnetConfig>(int step)> subnets,
                                 double distill, LossOptions loss, SRNetwork teacher) {
  if (teacher) {
    teacher->eval();
    for (auto& p : teacher->parameters()) p.set_requires_grad(false);
  }
  TrainHooks hooks;
  hooks.extra_loss = [network, subnets, distill, loss, teacher](const Batch& batch, const TrainOutput& full,
                                                                 int step) mutable {
    torch::Tensor total = torch::zeros({}, batch.lr_color.options());
    const auto chosen = subnets(step);
    if (chosen.empty()) return total;
    torch::Tensor target;
    if (distill > 0) {
      torch::NoGradGuard no_grad;
      target = teacher ? teacher->forward(batch.lr_color, teacher->info_input(batch)) : full.image.detach();
    }
    const torch::Tensor info = network->info_input(batch);
    for (const auto& sub : chosen) {
      const graph::Graph g = subnet_graph(*network, sub, /*training=*/false, /*differentiable=*/true);
      const torch::Tensor out = graph::run(g, network_inputs(g, batch.lr_color, info)).front().second;
      if (distill > 0) total = total + distill * reconstruction_error(out, target, loss.image_norm);
      if (distill < 1) total = total + (1 - distill) * reconstruction_error(out, batch.hr_color, loss.image_norm);
    }
    return total / static_cast<double>(chosen.size());
  };
  return hooks;
}

}  // namespace cgsr
