#pragma once
// Training an elastic network (models/elastic.h) once so that every subnet of its space works:
// each step trains the full network on the HR frame (the trainer's own loss), the smallest subnet
// and `sampled` random ones (the sandwich rule of universally slimmable networks), each subnet
// learning the full network's output of the same step (in-place distillation, detached) mixed
// with the HR frame. Subnets run as graphs whose weights are views of the full network's
// (models/subnet.h), so their gradients land on the shared weights.
//
// Progressive shrinking (Once-for-All): how far a step's subnets may shrink opens over the
// training, per dimension, from the full network at `start` to the whole space `ramp` later
// (fractions of the schedule's steps). depth {0, 0.25} and width {0.25, 0.25} train depth first,
// then width; both {0, 0} sample the whole space from the first step.
//
//   Trainer trainer(elastic.network, data, schedule, loss, {},
//                   elastic_training_hooks(elastic.network, elastic.space, options, schedule.steps, seed));

#include <cstdint>
#include <functional>
#include <vector>

#include "core/config.h"
#include "models/elastic.h"
#include "models/latency_table.h"
#include "models/sr_network.h"
#include "train/losses.h"
#include "train/trainer.h"

namespace cgsr {

struct ShrinkPhase {
  double start = 0;  // fraction of the steps where shrinking in this dimension begins
  double ramp = 0;   // fraction of the steps over which the whole range opens
};

struct ElasticTrainingOptions {
  bool enabled = false;   // train the network as an elastic network
  // Start from random weights of the model's architecture instead of its trained ones: the
  // elastic network then gets every step of its training, its subnets from the first (with
  // distill below 1 and a full-network warm-up: depth.start > 0; at distill 1 it collapses to its
  // image skip, docs/results/elastic.md).
  bool from_scratch = false;
  ElasticOptions space;
  int sampled = 2;        // random subnets per step besides the full network and the smallest
  double distill = 1.0;   // weight of the full network's output in a subnet's target (rest: HR)
  ShrinkPhase depth{0.0, 0.25};
  ShrinkPhase width{0.25, 0.25};
  LatencyTableOptions latency;  // the latency table measured after training, stored with the model
};
// `with_enabled`: the `enabled` key (a stage that always trains elastically leaves it out).
config::Schema<ElasticTrainingOptions> elastic_training_schema(bool with_enabled = true);

// How far subnets may shrink at `step` of `steps`.
ShrinkLimits shrink_limits(const ElasticTrainingOptions& options, int step, int steps);

// The subnets trained at `step` besides the full network: the smallest within the limits, then
// `sampled` random ones; the same for the same (seed, step), so a resumed run trains the same.
std::vector<SubnetConfig> step_subnets(const ElasticSpace& space, const ElasticTrainingOptions& options, int step,
                                       int steps, uint64_t seed);

// The trainer hooks: every step's extra loss is the mean of the step's subnets' losses, so the
// full network and the subnets weigh the same. (Their sum, three subnets against one full
// network, made the full network diverge within 100 steps at 1e-4 once subnets skipped blocks.)
TrainHooks elastic_training_hooks(SRNetwork network, const ElasticSpace& space, const ElasticTrainingOptions& options,
                                  LossOptions loss, int steps, uint64_t seed);

// The same for any choice of subnets per step (a pattern pool's, pruning/): each subnet's loss
// is distill * ||subnet - target|| + (1 - distill) * ||subnet - HR||, the target the output of
// `teacher` when given (run without gradients), else the network's own output of the step.
// The extra loss is their mean.
TrainHooks subnet_training_hooks(SRNetwork network, std::function<std::vector<SubnetConfig>(int step)> subnets,
                                 double distill, LossOptions loss, SRNetwork teacher = nullptr);

}  // namespace cgsr
