#pragma once
// Knowledge distillation: a network learns a trained teacher's output beside the HR frame. Each
// training step adds weight * ||student - teacher|| (the image norm of the loss) to the CGSR
// loss, the teacher run on the same batch without gradients. How the picked subnet of an elastic
// network and every control of equal latency (magnitude pruning, uniform width) are fine-tuned
// alike.
//
//   Trainer trainer(student, data, schedule, loss, {}, distillation_hooks(teacher, 1.0, loss.image_norm));

#include <string>

#include "core/config.h"
#include "models/sr_network.h"
#include "train/losses.h"
#include "train/trainer.h"

namespace cgsr {

struct DistillOptions {
  std::string teacher;  // model file; empty: no distillation
  double weight = 1.0;  // of the teacher term, beside the HR term's 1
  bool enabled() const { return !teacher.empty() && weight > 0; }
};
config::Schema<DistillOptions> distill_schema();

// The teacher must read a subset of the rendering channels the student's batches carry.
TrainHooks distillation_hooks(SRNetwork teacher, double weight, ErrorNorm norm);

}  // namespace cgsr
