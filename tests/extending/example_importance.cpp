// The importance criterion of docs/extending.md, as models/importance/activation_importance.cpp
// would hold it: how strongly each channel responds on real frames, where the magnitude
// criterion (channel_importance.h) looks at the weights alone.
#include <torch/torch.h>

#include "models/importance/channel_importance.h"

namespace cgsr {

// The mean absolute output of the op producing each channel (a convolution, before its
// activation function) over the frames `color`, with their rendering information `info` for a
// network with a RIT. One graph run; the observer sees every op's output.
FrameImportance activation_importance(const SRNetworkImpl& net, const torch::Tensor& color,
                                      const torch::Tensor& info) {
  torch::NoGradGuard no_grad;
  const graph::Graph g = net.describe(/*training=*/false);
  FrameImportance importance;
  graph::run(g, network_inputs(g, color, info), nullptr, [&](size_t index, const torch::Tensor& output) {
    const graph::Op& op = g.ops[index];
    if (op.trainable && graph::op_traits(op.kind).has_tensors)
      add_position_scores(importance, g.values[op.output].layout, output.abs().mean({0, 2, 3}));
    return output;
  });
  return importance;
}

}  // namespace cgsr
