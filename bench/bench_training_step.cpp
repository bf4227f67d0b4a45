// cgsr's training step alone, the work bench/pytorch_reference.py times in PyTorch: PAN x2 on a
// batch of random LR patches, the CGSR loss (L2 image term; --loss l1 or ssim for the others),
// backward, gradient-norm clipping and an Adam step, in NCHW and in channels-last. Data loading is not in it (`cgsr train`
// reports the whole stage's patches per second). Prints one JSON object: steps per
// second and, per layout, the milliseconds of a step spent in each phase.
//
//   bench_training_step [--batch 4] [--patch 24] [--steps 60] [--warmup 5] [--threads 2] [--loss l2]
#include <CLI/CLI.hpp>
#include <torch/torch.h>

#include <chrono>
#include <cstdio>
#include <string>

#include "core/runtime.h"
#include "models/arch_spec.h"
#include "models/memory_layout.h"
#include "train/losses.h"

using namespace cgsr;

namespace {

// Seconds spent in each phase of the timed steps.
struct StepPhases {
  double forward = 0, backward = 0, clip = 0, optimizer = 0;
};

double steps_per_second(MemoryLayout layout, int batch_size, int patch, int steps, int warmup, ErrorNorm norm,
                        StepPhases& phases) {
  seed_everything(0);
  SRNetwork net(default_spec("pan", 2));
  set_parameter_layout(*net, layout);
  net->train();
  torch::optim::Adam optimizer(net->parameters(), torch::optim::AdamOptions(1e-3));
  Batch batch;
  batch.scale = 2;
  batch.lr_color = to_layout(torch::rand({batch_size, 3, patch, patch}), layout);
  batch.hr_color = to_layout(torch::rand({batch_size, 3, 2 * patch, 2 * patch}), layout);
  LossOptions loss;
  loss.lambda_geometry = 0;
  loss.image_norm = norm;
  using Clock = std::chrono::steady_clock;
  const auto seconds_since = [](Clock::time_point& t) {
    const auto now = Clock::now();
    const double s = std::chrono::duration<double>(now - t).count();
    t = now;
    return s;
  };
  const auto step = [&](StepPhases& p) {
    auto t = Clock::now();
    const auto output = net->forward_train(batch.lr_color);
    const auto terms = cgsr_loss(*net, output, batch, loss);
    p.forward += seconds_since(t);
    optimizer.zero_grad();
    terms.total.backward();
    p.backward += seconds_since(t);
    torch::nn::utils::clip_grad_norm_(net->parameters(), 1.0);
    p.clip += seconds_since(t);
    optimizer.step();
    p.optimizer += seconds_since(t);
  };
  StepPhases ignored;
  for (int i = 0; i < warmup; ++i) step(ignored);
  const auto start = Clock::now();
  for (int i = 0; i < steps; ++i) step(phases);
  return steps / std::chrono::duration<double>(Clock::now() - start).count();
}

std::string phases_json(const StepPhases& p, int steps) {
  const auto ms = [&](double s) { return std::to_string(1e3 * s / steps); };
  return "{\"forward_and_loss\": " + ms(p.forward) + ", \"backward\": " + ms(p.backward) + ", \"clip\": " +
         ms(p.clip) + ", \"optimizer\": " + ms(p.optimizer) + "}";
}

}  // namespace

int main(int argc, char** argv) {
  int batch = 4, patch = 24, steps = 60, warmup = 5, threads = 2;
  std::string loss_name = enum_name(ErrorNorm::L2);
  CLI::App app{"cgsr's training step alone, in NCHW and channels-last"};
  app.add_option("--batch", batch, "patches per step")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--patch", patch, "LR patch side, pixels")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--steps", steps, "timed steps")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--warmup", warmup, "untimed steps first")->check(CLI::NonNegativeNumber)->capture_default_str();
  app.add_option("--threads", threads, "LibTorch and TBB threads (0 = all hardware threads)")->capture_default_str();
  app.add_option("--loss", loss_name, "the image loss")->check(CLI::IsMember(EnumNames<ErrorNorm>::names()))->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  const ErrorNorm norm = enum_from_name<ErrorNorm>(loss_name);
  set_threads(threads);
  StepPhases nchw_phases, nhwc_phases;
  const double nchw = steps_per_second(MemoryLayout::Nchw, batch, patch, steps, warmup, norm, nchw_phases);
  const double nhwc = steps_per_second(MemoryLayout::Nhwc, batch, patch, steps, warmup, norm, nhwc_phases);
  std::printf("{\"threads\": %d, \"loss\": \"%s\", \"batch\": %d, \"patch\": %d, \"steps\": %d, "
              "\"train_steps_per_second\": {\"nchw\": %.3f, \"nhwc\": %.3f}, "
              "\"ms_per_step\": {\"nchw\": %s, \"nhwc\": %s}}\n",
              threads, enum_name(norm).c_str(), batch, patch, steps, nchw, nhwc, phases_json(nchw_phases, steps).c_str(),
              phases_json(nhwc_phases, steps).c_str());
  return 0;
}
