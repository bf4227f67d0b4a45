#pragma once
// Fast inference of an inference graph (graph.h) with oneDNN primitives instead of the
// interpreter's one-LibTorch-call-per-op:
//   - convolutions get their weights reordered once into the layout their kernel asks for;
//     among oneDNN's kernels for a convolution the fastest is measured once per problem;
//   - activations stay in one layout between ops (channels-last by default: no channel padding
//     at widths like 20 or 13, and jit kernels for every op PAN needs);
//   - the element-wise ops after a convolution (ReLU, LeakyReLU, sigmoid, a residual add, an
//     attention product, a channel affine, and chains of them) become its post-ops, when the
//     intermediate values have no other consumer and oneDNN has a jit kernel for the chain; a
//     residual nothing reads afterwards is summed into in place;
//   - a concatenation read only by 1x1 convolutions is never built: each such convolution runs
//     once per part and sums the parts in its output (sum post-op);
//   - resizes (nearest, bilinear), average pooling, pixel shuffle and the remaining element-wise
//     ops are oneDNN primitives; bicubic resizing goes through graph::apply_resize (LibTorch);
//   - with Precision::Bf16 or Int8 (precision.h), convolutions compute in that format, except the
//     wide ones: those reading the graph's inputs (colour, depth spanning decades) and those
//     writing its outputs. A value is stored in the low format when every op reading it is a
//     low-precision convolution; otherwise it stays float32 (residuals, attention maps, the
//     operands of element-wise ops), and a low-precision convolution reading it gets a converted
//     copy made once. Element-wise post-ops compute in float32 on the dequantized result.
// In float32 the result equals graph::run up to float rounding (different summation orders), for finite
// input: oneDNN's fused ReLU turns NaN into 0 where LibTorch keeps it (data sets reject
// non-finite frames when they load, so no data path feeds NaN).
//
//   FusedGraph fast(net->describe());         // snapshot of the weights
//   auto sr = fast.run(lr_color);             // [N, 3, s*h, s*w], contiguous NCHW float32
//
// The object copies the graph's tensors when constructed: it does not see later changes to the
// network (training, pruning, loading weights); construct a new one then. The first run for an
// input size (N, h, w) compiles a plan (kernel choice, primitives, weight reorders, buffers);
// plans for the last few sizes are kept. Threads are oneDNN's OpenMP threads
// (torch::set_num_threads). One run at a time per object (plans own their buffers). No autograd.

#include <torch/types.h>

#include <cstdint>
#include <list>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "models/graph.h"
#include "models/precision.h"

namespace cgsr {

class FusedGraph {
 public:
  enum class Layout {
    ChannelsLast,  // nhwc
    Blocked,       // nChw16c with AVX-512, nChw8c otherwise (channels padded to the block)
  };
  struct Options {
    Layout layout = Layout::ChannelsLast;
    bool fuse = true;          // post-op fusion; false runs every op as its own primitive
    bool split_concat = true;  // false: concatenations are copied into one buffer
    bool sum_in_place = true;  // a residual add writes into the residual's buffer (sum post-op) when
                               // nothing reads the residual later; false: a binary post-op reads it
    bool tune = false;         // time oneDNN's kernels for each distinct convolution (once per process
                               // and problem, single-threaded CPU time) and keep the fastest. Off by
                               // default: a choice made by timing can differ between two runs, and
                               // so could their last bits (evaluations must reproduce exactly)
    size_t cached_plans = 4;   // plans kept for different input sizes
    Precision precision = Precision::Fp32;
    Calibration calibration;   // Int8: the ranges of the graph's values (calibrate())
    std::vector<bool> low_convs;  // which ops compute in `precision`, indexed like the graph's ops
                                  // (true only for convolutions); empty: low_precision_convs(graph).
                                  // The latency table times a lone convolution as an inner one
  };

  // What a plan executes, one entry per step, in order (for tests, logs and profiles).
  struct Step {
    std::string kind;                // "conv", "binary", "eltwise", "resampling", "torch", ...
    std::vector<std::string> ops;    // names of the graph ops it computes, the first one leading
    std::string implementation;      // oneDNN's implementation ("jit:avx512_core", ...) or "torch"
    std::string precision = "fp32";  // the format it computes in: "fp32", "bf16" or "int8"
  };

  explicit FusedGraph(const graph::Graph& graph);
  FusedGraph(const graph::Graph& graph, Options options);
  ~FusedGraph();
  FusedGraph(FusedGraph&&) noexcept;
  FusedGraph& operator=(FusedGraph&&) noexcept;

  // `inputs` maps every graph input name to an NCHW float32 CPU tensor: graph input i is
  // [N, C_i, h * f_i, w * f_i] for its width C_i and factor f_i (graph.h). Returns every graph
  // output, contiguous NCHW. Wrong names, shapes or types throw cgsr::Error.
  std::vector<std::pair<std::string, torch::Tensor>> run(
      const std::vector<std::pair<std::string, torch::Tensor>>& inputs);
  // An SR network's graph: inputs "color" (and the RIT's "info" or "info_hr"), output "image".
  torch::Tensor run(const torch::Tensor& color, const torch::Tensor& info = {});

  // The steps of the plan the last run used (empty before the first run).
  const std::vector<Step>& steps() const;
  std::string plan_string() const;  // one line per step
  const Options& options() const { return options_; }

 private:
  struct Plan;
  Plan& plan_for(const std::vector<std::pair<std::string, torch::Tensor>>& inputs);

  graph::Graph graph_;  // with its own copies of every tensor
  Options options_;
  std::list<std::unique_ptr<Plan>> plans_;  // most recently used first
};

}  // namespace cgsr
