// Elastic training (train/elastic_training.h) and distillation (train/distillation.h) on the tiny
// rendered scene: the subnets a step trains are a function of (seed, step), progressive
// shrinking opens the space over the schedule, and training moves the subnets toward the full
// network's output.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include "core/runtime.h"
#include "models/arch_spec.h"
#include "models/elastic.h"
#include "render_data/patch_sampler.h"
#include "tests/support/elastic_options.h"
#include "tests/support/tiny_data.h"
#include "train/distillation.h"
#include "train/elastic_training.h"

using namespace cgsr;
using namespace cgsr::test;

namespace {

ArchSpec elastic_pan() { return spec_from_yaml("backbone: pan\nscale: 2\nblocks: 3\n", "test"); }

TrainSchedule short_schedule(int steps) {
  TrainSchedule s;
  s.steps = steps;
  s.batch_size = 2;
  s.patch_size = 16;
  s.validate_every = 0;
  s.val_frames = 1;
  s.layout = MemoryLayout::Nchw;
  return s;
}

// Mean absolute difference between a subnet's output and the full network's on a validation frame.
double gap_to_full(const SRNetworkImpl& net, const SubnetConfig& sub, const Batch& b) {
  torch::NoGradGuard no_grad;
  const graph::Graph g = subnet_graph(net, sub);
  const auto small = graph::run(g, network_inputs(g, b.lr_color, {})).front().second;
  const auto full = graph::run(net.describe(false), network_inputs(net.describe(false), b.lr_color, {})).front().second;
  return (small - full).abs().mean().item<double>();
}

}  // namespace

TEST(ElasticTraining, ShrinkingOpensByPhase) {
  ElasticTrainingOptions o;
  o.depth = {0.0, 0.5};
  o.width = {0.5, 0.25};
  EXPECT_EQ(shrink_limits(o, 0, 100).depth, 0);
  EXPECT_DOUBLE_EQ(shrink_limits(o, 25, 100).depth, 0.5);
  EXPECT_EQ(shrink_limits(o, 25, 100).width, 0);
  EXPECT_DOUBLE_EQ(shrink_limits(o, 60, 100).width, 0.4);
  EXPECT_EQ(shrink_limits(o, 90, 100).width, 1);
  EXPECT_EQ(shrink_limits(o, 90, 100).depth, 1);
}

TEST(ElasticTraining, StepSubnetsAreAFunctionOfSeedAndStep) {
  const ElasticSpace space(elastic_pan(), test::elastic_options(4, 0.25, 1));
  ElasticTrainingOptions o;
  o.sampled = 3;
  o.depth = {0, 0};
  o.width = {0, 0};
  const auto a = step_subnets(space, o, 7, 100, 1), b = step_subnets(space, o, 7, 100, 1);
  ASSERT_EQ(a.size(), 4u);
  for (size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i], b[i]);
  EXPECT_EQ(a.front(), space.smallest());
  const auto c = step_subnets(space, o, 8, 100, 1);
  EXPECT_NE(subnet_key(a[1]) + subnet_key(a[2]), subnet_key(c[1]) + subnet_key(c[2]));
  // Before any dimension opens, only the full network trains.
  o.depth = {0.5, 0.1};
  o.width = {0.5, 0.1};
  EXPECT_TRUE(step_subnets(space, o, 10, 100, 1).empty());
}

TEST(ElasticTraining, SandwichTrainingBringsTheSmallestSubnetTowardTheFull) {
  set_threads(1);
  seed_everything(5);
  const Dataset data = Dataset::open(tiny_data());
  SRNetwork trained(elastic_pan());
  Trainer(trained, data, short_schedule(30), LossOptions{}).run();
  ElasticOptions space_options = test::elastic_options(4, 0.5, 1);
  const ElasticNetwork elastic = make_elastic(*trained, space_options);
  const Batch val = frame_batch(data, data.frames(Split::Val).front(), 2, {}, DepthEncoding::Log);
  const SubnetConfig smallest = elastic.space.smallest();
  const double before = gap_to_full(*elastic.network, smallest, val);
  ElasticTrainingOptions o;
  o.space = space_options;
  o.depth = {0, 0};
  o.width = {0, 0};
  const TrainSchedule schedule = short_schedule(30);
  Trainer(elastic.network, data, schedule, LossOptions{}, {},
          elastic_training_hooks(elastic.network, elastic.space, o, LossOptions{}, schedule.steps, 1))
      .run();
  EXPECT_LT(gap_to_full(*elastic.network, smallest, val), before);
}

TEST(Distillation, TeacherTermPullsTheStudentToTheTeacher) {
  set_threads(1);
  seed_everything(6);
  const Dataset data = Dataset::open(tiny_data());
  SRNetwork teacher(elastic_pan());
  Trainer(teacher, data, short_schedule(20), LossOptions{}).run();
  const Batch val = frame_batch(data, data.frames(Split::Val).front(), 2, {}, DepthEncoding::Log);
  const auto distance = [&](SRNetwork student) {
    torch::NoGradGuard no_grad;
    return (student->forward(val.lr_color) - teacher->forward(val.lr_color)).abs().mean().item<double>();
  };
  double gap[2];
  for (int distilled = 0; distilled < 2; ++distilled) {
    seed_everything(7);
    SRNetwork student(elastic_pan());
    const TrainHooks hooks = distilled ? distillation_hooks(teacher, 20.0, ErrorNorm::L1) : TrainHooks{};
    Trainer(student, data, short_schedule(20), LossOptions{}, {}, hooks).run();
    gap[distilled] = distance(student);
  }
  EXPECT_LT(gap[1], gap[0]);
}
