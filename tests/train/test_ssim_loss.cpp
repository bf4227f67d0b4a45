// The SSIM training loss (loss.image_norm: ssim): 1 - the SSIM metric's value, differentiable,
// with finite gradients on flat and extreme images, and usable for a training step.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include "core/config.h"
#include "core/error.h"
#include "core/metrics.h"
#include "core/runtime.h"
#include "models/arch_spec.h"
#include "tests/support/tiny_data.h"
#include "train/losses.h"
#include "train/trainer.h"

using namespace cgsr;
using namespace cgsr::test;

namespace {

// A random image and a noisy, shifted copy (SSIM well inside (0, 1)).
std::pair<torch::Tensor, torch::Tensor> random_pair(torch::ScalarType type) {
  torch::manual_seed(11);
  const auto a = torch::rand({2, 3, 29, 23}, type);
  const auto b = (0.8 * a.roll(1, 3) + 0.2 * torch::rand_like(a)).clamp(0, 1);
  return {a, b};
}

// Gradient of the loss with respect to `output` (target fixed).
torch::Tensor gradient(const torch::Tensor& output, const torch::Tensor& target) {
  const auto x = output.clone().requires_grad_(true);
  ssim_loss(x, target).backward();
  return x.grad();
}

}  // namespace

TEST(SsimLoss, IdenticalImagesGiveZero) {
  const auto [a, b] = random_pair(torch::kFloat32);
  EXPECT_NEAR(ssim_loss(a, a).item<double>(), 0.0, 1e-6);
  EXPECT_NEAR(ssim_loss(b, b).item<double>(), 0.0, 1e-6);
  EXPECT_GT(ssim_loss(a, b).item<double>(), 0.05);  // and a different image does not
}

TEST(SsimLoss, EqualsOneMinusTheMetric) {
  for (const auto type : {torch::kFloat32, torch::kFloat64}) {
    const auto [a, b] = random_pair(type);
    const double metric = ssim(a, b).mean().item<double>();
    // float64 runs the metric's arithmetic in another order; float32 rounds the statistics.
    EXPECT_NEAR(ssim_loss(a, b).item<double>(), 1.0 - metric, type == torch::kFloat64 ? 1e-12 : 2e-6) << type;
    EXPECT_NEAR(ssim_loss(a[0], b[0]).item<double>(), 1.0 - ssim(a[0], b[0]).item<double>(),
                type == torch::kFloat64 ? 1e-12 : 2e-6);  // CHW too
  }
}

TEST(SsimLoss, ReconstructionErrorWithTheSsimNormIsTheSsimLoss) {
  const auto [a, b] = random_pair(torch::kFloat32);
  EXPECT_EQ(reconstruction_error(a, b, ErrorNorm::Ssim).item<double>(), ssim_loss(a, b).item<double>());
  const auto doc = config::Document::parse("image_norm: ssim\n", "loss.yaml");
  EXPECT_EQ(config::parse_document(doc, loss_schema()).image_norm, ErrorNorm::Ssim);
}

TEST(SsimLoss, GradientsAreFiniteOnFlatAndExtremeImages) {
  const auto [a, b] = random_pair(torch::kFloat32);
  const auto zeros = torch::zeros_like(a), ones = torch::ones_like(a), large = torch::full_like(a, 1000.0);
  const std::vector<std::pair<torch::Tensor, torch::Tensor>> cases = {
      {zeros, zeros}, {ones, ones},  {zeros, ones}, {ones, zeros}, {a, zeros},
      {a, ones},      {large, a},    {a * 1000, b}, {large, large}, {a, b}};
  for (size_t i = 0; i < cases.size(); ++i) {
    const auto& [output, target] = cases[i];
    EXPECT_TRUE(std::isfinite(ssim_loss(output, target).item<double>())) << "case " << i;
    const auto g = gradient(output, target);
    ASSERT_TRUE(g.defined()) << "case " << i;
    EXPECT_TRUE(torch::isfinite(g).all().item<bool>()) << "case " << i;
  }
  // Not a zero gradient everywhere: descending it brings a different image closer.
  const auto g = gradient(a, b);
  EXPECT_GT(g.abs().max().item<double>(), 0.0);
  EXPECT_LT(ssim_loss(a - 50.0 * g, b).item<double>(), ssim_loss(a, b).item<double>());
}

TEST(SsimLoss, SmallOrMismatchedImagesAreErrors) {
  const auto small = torch::rand({1, 3, 10, 40});
  EXPECT_THROW(ssim_loss(small, small), Error);
  const auto a = torch::rand({1, 3, 16, 16});
  EXPECT_THROW(ssim_loss(a, torch::rand({1, 3, 16, 17})), Error);
  EXPECT_THROW(ssim_loss(torch::rand({16, 16}), torch::rand({16, 16})), Error);
}

TEST(SsimLoss, OneTrainingStepWithIt) {
  set_threads(1);
  seed_everything(3);
  SRNetwork net(spec_from_yaml("backbone: pan\nscale: 2\nblocks: 2\n", "test"));
  std::vector<torch::Tensor> before;
  for (const auto& p : net->parameters()) before.push_back(p.detach().clone());
  TrainSchedule schedule;
  schedule.steps = 1;
  schedule.batch_size = 2;
  schedule.patch_size = 16;  // HR patches of 32x32: room for the 11x11 window
  schedule.validate_every = 0;
  schedule.val_frames = 1;
  LossOptions loss;
  loss.image_norm = ErrorNorm::Ssim;
  const TrainOutcome outcome = Trainer(net, Dataset::open(tiny_data()), schedule, loss).run();
  EXPECT_EQ(outcome.steps, 1);
  EXPECT_EQ(outcome.skipped_steps, 0);
  ASSERT_EQ(outcome.loss_curve.size(), 1u);
  EXPECT_TRUE(std::isfinite(outcome.loss_curve[0]));
  EXPECT_GT(outcome.loss_curve[0], 0.0);
  EXPECT_TRUE(std::isfinite(outcome.best.image_loss));
  double moved = 0;
  const auto after = net->parameters();
  for (size_t i = 0; i < before.size(); ++i) moved = std::max(moved, (after[i] - before[i]).abs().max().item<double>());
  EXPECT_GT(moved, 0.0);
}
