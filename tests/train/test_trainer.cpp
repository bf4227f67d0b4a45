// The trainer on a tiny rendered scene: the memory layout of its steps changes results only
// within float tolerance, the network comes back in NCHW, and the choice is recorded.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include "core/runtime.h"
#include "models/arch_spec.h"
#include "tests/support/tiny_data.h"
#include "train/trainer.h"

using namespace cgsr;
using namespace cgsr::test;

namespace {

ArchSpec small_pan() { return spec_from_yaml("backbone: pan\nscale: 2\nblocks: 2\n", "test"); }

TrainSchedule short_schedule(const std::string& layout) {
  TrainSchedule s;
  s.steps = 6;
  s.batch_size = 2;
  s.patch_size = 16;
  s.validate_every = 0;
  s.val_frames = 1;
  s.layout = layout;
  return s;
}

// Trains a fresh small PAN (same seed each time) and returns it with the outcome.
std::pair<SRNetwork, TrainOutcome> train(const std::string& layout) {
  seed_everything(3);
  SRNetwork net(small_pan());
  const Dataset data = Dataset::open(tiny_data());
  Trainer trainer(net, data, short_schedule(layout), LossOptions{});
  TrainOutcome outcome = trainer.run();
  return {net, outcome};
}

}  // namespace

TEST(Trainer, LayoutsTrainToTheSameWeightsWithinTolerance) {
  set_threads(1);
  const auto [nchw, nchw_outcome] = train("nchw");
  const auto [nhwc, nhwc_outcome] = train("nhwc");
  EXPECT_EQ(nchw_outcome.layout, "nchw");
  EXPECT_EQ(nhwc_outcome.layout, "nhwc");
  const auto a = nchw->parameters(), b = nhwc->parameters();
  ASSERT_EQ(a.size(), b.size());
  double worst = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    // Handed back in NCHW whatever the steps ran in.
    EXPECT_TRUE(b[i].is_contiguous()) << i;
    worst = std::max(worst, (a[i] - b[i]).abs().max().item<double>());
  }
  // Six Adam steps of lr 1e-3 move weights by up to ~6e-3; the layouts agree far below that.
  EXPECT_LT(worst, 1e-4);
  EXPECT_NEAR(nchw_outcome.best.psnr, nhwc_outcome.best.psnr, 1e-3);
}

TEST(Trainer, SameLayoutAndSeedIsBitIdentical) {
  set_threads(1);
  const auto [first, first_outcome] = train("nhwc");
  const auto [second, second_outcome] = train("nhwc");
  const auto a = first->parameters(), b = second->parameters();
  for (size_t i = 0; i < a.size(); ++i) EXPECT_TRUE(torch::equal(a[i], b[i])) << i;
}

TEST(Trainer, AutoLayoutRecordsItsChoice) {
  set_threads(1);
  const auto [net, outcome] = train("auto");
  EXPECT_TRUE(outcome.layout == "nchw" || outcome.layout == "nhwc") << outcome.layout;
  for (const auto& p : net->parameters()) EXPECT_TRUE(p.is_contiguous());
}

// Adam's first step moves every weight with a gradient by the learning rate, so after one step
// the largest change per part is that part's rate: the RIT's is rit_lr_scale times the backbone's.
TEST(Trainer, RenderingInformationPartsLearnAtTheirOwnRate) {
  set_threads(1);
  seed_everything(3);
  SRNetwork net(spec_from_yaml(
      "backbone: pan\nscale: 2\nblocks: 2\nrit: {enabled: true, channels: [depth, edge], source: hr_fuse}\n", "test"));
  std::vector<std::pair<std::string, torch::Tensor>> before;
  for (const auto& item : net->named_parameters()) before.emplace_back(item.key(), item.value().detach().clone());
  TrainSchedule schedule = short_schedule("nchw");
  schedule.steps = 1;
  schedule.lr_max = schedule.lr_min = 1e-3;
  schedule.rit_lr_scale = 10;
  const Dataset data = Dataset::open(tiny_data());
  Trainer(net, data, schedule, LossOptions{}).run();

  double backbone = 0, rit = 0;
  const auto after = net->named_parameters();
  for (const auto& [key, value] : before) {
    const double moved = (after[key] - value).abs().max().item<double>();
    double& part = key.rfind("rit.", 0) == 0 ? rit : backbone;
    part = std::max(part, moved);
  }
  EXPECT_NEAR(backbone, 1e-3, 1e-5);
  EXPECT_NEAR(rit, 1e-2, 1e-4);
}
