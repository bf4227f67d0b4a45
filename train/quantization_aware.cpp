#include "train/quantization_aware.h"

#include "models/subnet.h"

namespace cgsr {

TrainHooks quantization_aware(TrainHooks hooks, SRNetwork network, Calibration calibration) {
  hooks.forward = [network, calibration](const Batch& batch, int) {
    const graph::Graph g =
        subnet_graph(*network, full_subnet(network->spec()), /*training=*/false, /*differentiable=*/true);
    TrainOutput out;
    out.image = run_fake_int8(g, network_inputs(g, batch.lr_color, network->info_input(batch)), calibration)
                    .front()
                    .second;
    return out;
  };
  return hooks;
}

}  // namespace cgsr
