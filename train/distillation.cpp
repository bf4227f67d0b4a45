#include "train/distillation.h"

#include <torch/torch.h>

namespace cgsr {

config::Schema<DistillOptions> distill_schema() {
  config::Schema<DistillOptions> s;
  s.field("teacher", &DistillOptions::teacher, "model file of the teacher (empty: no distillation)");
  s.field("weight", &DistillOptions::weight, "weight of the teacher term beside the HR term's 1").range(0, 100);
  return s;
}

TrainHooks distillation_hooks(SRNetwork teacher, double weight, ErrorNorm norm) {
  teacher->eval();
  for (auto& p : teacher->parameters()) p.set_requires_grad(false);
  TrainHooks hooks;
  hooks.extra_loss = [teacher, weight, norm](const Batch& batch, const TrainOutput& output, int) mutable {
    torch::Tensor target;
    {
      torch::NoGradGuard no_grad;
      target = teacher->forward(batch.lr_color, teacher->info_input(batch));
    }
    return weight * reconstruction_error(output.image, target, norm);
  };
  return hooks;
}

}  // namespace cgsr
