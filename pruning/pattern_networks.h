#pragma once
// The patterns of a pool (pattern_pool.h) as networks that run: pattern k is the network's
// subnet graph (models/subnet.h), executed by cgsr's fast path (models/fused_graph.h) like any
// static network. Choosing a pattern per frame costs nothing beyond running that pattern: every
// pattern is built before the first frame, and no weights move.
//
//   PatternNetworks patterns(*net, pool);
//   auto sr = patterns.run(2, lr_color, net->info_input(batch));   // pattern 2 of the pool

#include <torch/types.h>

#include <memory>
#include <vector>

#include "core/timing.h"
#include "models/complexity.h"
#include "models/fused_graph.h"
#include "models/graph.h"
#include "models/sr_network.h"
#include "models/subnet.h"
#include "pruning/pattern_pool.h"

namespace cgsr {

// How INT8 patterns are calibrated: the frames' graph inputs (each pattern's graph reads the same
// names) and the method.
struct PatternCalibration {
  std::vector<std::vector<std::pair<std::string, torch::Tensor>>> frames;
  CalibrationMethod method = CalibrationMethod::Percentile;
};

class PatternNetworks {
 public:
  // Reads `net`'s weights now (later changes to the network are not seen). The pool must
  // belong to the network (pool.spec). Every pattern runs in `precision` (bf16, int8: the wide
  // layers stay float32, models/fused_graph.h); int8 calibrates each pattern's own graph.
  PatternNetworks(const SRNetworkImpl& net, PatternPool pool, Precision precision = Precision::Fp32,
                  const PatternCalibration& calibration = {});
  ~PatternNetworks();

  int size() const { return pool_.size(); }
  Precision precision() const { return precision_; }
  const PatternPool& pool() const { return pool_; }

  // The subnet graph of pattern k.
  const graph::Graph& graph(int k) const;
  // [N, 3, s*h, s*w]; `info` as for SRNetworkImpl::forward (undefined without RIT). No autograd.
  torch::Tensor run(int k, const torch::Tensor& lr_color, const torch::Tensor& info);
  Complexity cost(int k, int64_t lr_width, int64_t lr_height) const;

  // Every pattern timed on one input in interleaved rounds (after two warm-up runs each).
  std::vector<LatencyStats> measure_latency(const torch::Tensor& lr_color, const torch::Tensor& info, int rounds);

 private:
  PatternPool pool_;
  std::vector<graph::Graph> graphs_;
  Precision precision_;
  std::vector<FusedGraph::Options> options_;  // per pattern
  std::vector<std::unique_ptr<FusedGraph>> fused_;  // all built at the first run
};

}  // namespace cgsr
