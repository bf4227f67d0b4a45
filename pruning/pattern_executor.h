#pragma once
// Runs a network with one pattern per pruning unit as smaller dense convolutions.
//
// For every (unit, pattern) of the pool the executor gathers, once, the rows and columns of the
// unit's weights that the pattern keeps (channel_selection.h). Executing a choice then swaps
// those tensors into a working copy of the graph (only the units whose pattern changed) and runs
// the graph interpreter: choosing a pattern per frame copies no weights.
//
//   PatternExecutor exec(*net, pool);
//   auto sr = exec.run(lr_color, info, {2, 0, 5, ...});   // one pattern index per unit

#include <torch/types.h>

#include <vector>

#include "models/complexity.h"
#include "models/graph.h"
#include "models/sr_network.h"
#include "pruning/pattern_pool.h"

namespace cgsr {

class PatternExecutor {
 public:
  // `net` must outlive the executor; its weights are read when the executor is built.
  PatternExecutor(const SRNetworkImpl& net, PatternPool pool);

  // [N, 3, s*h, s*w]; `info` as for SRNetworkImpl::forward (undefined without RIT). No autograd.
  torch::Tensor run(const torch::Tensor& lr_color, const torch::Tensor& info, const std::vector<int>& choice);

  // The narrowed graph of a choice (for complexity counting and export-style inspection).
  const graph::Graph& graph_for(const std::vector<int>& choice);
  Complexity cost(const std::vector<int>& choice, int64_t lr_width, int64_t lr_height);

  const PatternPool& pool() const { return pool_; }

 private:
  struct OpTensors {
    size_t op;
    torch::Tensor weight, bias, scale, shift;
  };
  struct Prepared {
    std::vector<OpTensors> ops;                        // the unit's ops under the pattern
    std::vector<std::pair<int, graph::Layout>> layouts;  // narrowed layouts of the unit's values
  };
  void apply(const std::vector<int>& choice);

  PatternPool pool_;
  graph::Graph working_;
  std::vector<std::vector<Prepared>> prepared_;  // [unit][pattern]
  std::vector<int> current_;                    // pattern applied per unit (-1: none yet)
};

}  // namespace cgsr
