// cgsr's training step alone, the work bench/pytorch_reference.py times in PyTorch: PAN x2 on a
// batch of random LR patches, the CGSR loss (L2 image term), backward, gradient-norm clipping
// and an Adam step, in NCHW and in channels-last. Data loading is not in it (`cgsr train`
// reports the whole stage's patches per second). Prints one JSON object.
//
//   bench_training_step [--batch 4] [--patch 24] [--steps 60] [--warmup 5] [--threads 2]
#include <torch/torch.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "core/runtime.h"
#include "models/arch_spec.h"
#include "models/memory_layout.h"
#include "train/losses.h"

using namespace cgsr;

namespace {

double steps_per_second(MemoryLayout layout, int batch_size, int patch, int steps, int warmup) {
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
  const auto step = [&] {
    const auto output = net->forward_train(batch.lr_color);
    const auto terms = cgsr_loss(*net, output, batch, loss);
    optimizer.zero_grad();
    terms.total.backward();
    torch::nn::utils::clip_grad_norm_(net->parameters(), 1.0);
    optimizer.step();
  };
  for (int i = 0; i < warmup; ++i) step();
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < steps; ++i) step();
  return steps / std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

int main(int argc, char** argv) {
  int batch = 4, patch = 24, steps = 60, warmup = 5, threads = 2;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    const int value = std::atoi(argv[i + 1]);
    if (flag == "--batch") batch = value;
    else if (flag == "--patch") patch = value;
    else if (flag == "--steps") steps = value;
    else if (flag == "--warmup") warmup = value;
    else if (flag == "--threads") threads = value;
    else {
      std::fprintf(stderr, "usage: bench_training_step [--batch N] [--patch N] [--steps N] [--warmup N] [--threads N]\n");
      return 2;
    }
  }
  set_threads(threads);
  const double nchw = steps_per_second(MemoryLayout::Nchw, batch, patch, steps, warmup);
  const double nhwc = steps_per_second(MemoryLayout::Nhwc, batch, patch, steps, warmup);
  std::printf("{\"threads\": %d, \"batch\": %d, \"patch\": %d, \"steps\": %d, "
              "\"train_steps_per_second\": {\"nchw\": %.3f, \"nhwc\": %.3f}}\n",
              threads, batch, patch, steps, nchw, nhwc);
  return 0;
}
