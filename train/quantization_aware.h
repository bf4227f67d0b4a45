#pragma once
// Quantization-aware fine-tuning: training steps and validation run the network's inference
// graph with INT8 simulated (models/precision.h run_fake_int8), so its weights adapt to the
// rounding the fused INT8 path applies. For a network whose post-training INT8 loses too much;
// the ranges stay those calibrated before the fine-tuning.
//
//   hooks = quantization_aware(hooks, network, calibrate_network(*network, data, {}));

#include "models/precision.h"
#include "models/sr_network.h"
#include "train/trainer.h"

namespace cgsr {

// `hooks` with its forward replaced by the simulated-INT8 inference graph (its extra loss, such
// as distillation's, still added). The output has no geometry: the geometry head is not part of
// the inference graph, so its loss term is left out.
TrainHooks quantization_aware(TrainHooks hooks, SRNetwork network, Calibration calibration);

}  // namespace cgsr
