#pragma once
// An explicit, ordered description of a network's inference computation: the contract between
// the models and everything that walks a network layer by layer (complexity counting,
// inheritance, exporters to ONNX/TorchScript, pruning).
//
// A Graph is a list of Values (4-D NCHW tensors) and Ops in topological order. Every network
// writes its graph by hand, op for op in the same order as its forward(); the interpreter run()
// executes a graph with the very same kernels as the modules (the apply_* functions below), and
// the tests check that run(graph) equals forward() bit for bit. Conv and ChannelAffine ops hold
// the modules' own tensors (not copies), so a graph built from a network sees its current
// weights, and writing into op.weight writes the parameter.
//
// Op semantics (inputs -> output; every op has exactly one output value):
//   Conv           [x] -> conv2d(x, weight [out, in/groups, k, k], bias [out] or undefined,
//                  stride, padding (zeros, same on all sides), dilation, groups).
//                  `trainable` false marks fixed colour transforms (constants, no parameters:
//                  EDSR's mean shift, SRCNN's luma conversion).
//   Relu           [x] -> max(x, 0)
//   LeakyRelu      [x] -> x >= 0 ? x : negative_slope * x
//   Sigmoid        [x] -> 1 / (1 + exp(-x))
//   PixelShuffle   [x] -> depth-to-space by `factor` r: input channel c*r*r + i*r + j goes to
//                  output channel c at sub-pixel (i, j) (PyTorch PixelShuffle, ONNX
//                  DepthToSpace mode CRD).
//   Resize         [x] -> upsampling by the integer `factor` with `mode`, align_corners=False
//                  (half-pixel centres: output pixel j samples input (j + 0.5) / factor - 0.5).
//                  Nearest replicates each pixel factor x factor times. Bilinear and Bicubic
//                  clamp sample indices at the border; Bicubic uses a = -0.75 (PyTorch, ONNX
//                  Resize cubic_coeff_a=-0.75, exclude_outside=0). No antialiasing.
//   AvgPool        [x] -> average over non-overlapping factor x factor windows (kernel = stride
//                  = factor, no padding): area downsampling of an HR map to LR.
//   ChannelAffine  [x] -> x * scale[c] + shift[c] per channel; scale or shift may be undefined
//                  (then 1 or 0). Tensors have shape [C]. Used for the RIT gate (a trainable
//                  scale).
//   Add, Mul       [a, b] -> element-wise; operands have identical shapes (no broadcasting).
//   Concat         [a, b, ...] -> concatenation along channels.
//   Sample         [source (factor a), offsets (factor b, 2 fixed channels dx, dy)] -> the
//                  source's channels at factor b; b must be a multiple of a, r = b / a. Output
//                  pixel (i, j) reads the source at x = (j + 0.5) / r - 0.5 + dx(i, j),
//                  y = (i + 0.5) / r - 0.5 + dy(i, j), in source pixels (half-pixel centres, so
//                  zero offsets are nearest/bilinear upsampling by r; r = 1 warps by a motion
//                  field). `mode` Nearest rounds x and y half to even (nearbyint) and clamps the
//                  index to the image; Bilinear clamps x and y to [0, size - 1] and interpolates
//                  (border padding); Bicubic (a = -0.75) reads the 4x4 pixels around x, y, each
//                  index clamped to the image. Computed as grid_sampler(source, grid, align_corners=False,
//                  padding border) with the normalized grid of sample_grid() below, which the
//                  exporters write with the same float operations (ONNX GridSample, opset 16).
//   AnyAbsAbove    [x] -> 1 channel (fixed "mask"): 1 where max over channels |x[c]| > threshold,
//                  else 0. With threshold 0.5 it is the indicator round(x) != 0 (half to even:
//                  round(+-0.5) = 0), SRPO's "this pixel was moved" (models/backbones/srpo.h).
//
// Values carry a channel Layout: which prunable layer group (see arch_spec.h) owns each channel
// position. Ops that tie channels together (Add, Mul) require identical layouts, so a graph can
// only be built when widths are consistent through residual additions and attention products.
// A pixel-shuffle producer's output axis has `repeat` r*r: position c*r*r + k belongs to channel
// c of the group. Fixed axes (RGB, Y, rendering channels) are segments with prunable = false.
//
// Spatial sizes are kept as an integer `factor` relative to the LR input (the colour input has
// factor 1, an HR rendering-information input has factor = scale), so one graph serves every
// input size.

#include <torch/types.h>

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace cgsr::graph {

struct Segment {
  std::string group;     // layer group name (prunable) or fixed axis name ("rgb", "y", "info:depth")
  int64_t channels = 0;  // distinct channels of the group in this segment
  int64_t repeat = 1;    // consecutive positions per channel (r*r before a pixel shuffle)
  bool prunable = true;
  bool operator==(const Segment& o) const {
    return group == o.group && channels == o.channels && repeat == o.repeat && prunable == o.prunable;
  }
};
using Layout = std::vector<Segment>;

Layout group_layout(const std::string& group, int64_t channels, int64_t repeat = 1);  // prunable
Layout fixed_layout(const std::string& name, int64_t channels);
int64_t layout_width(const Layout& layout);
std::string layout_string(const Layout& layout);  // "features(40) + rit(16)"

struct Value {
  std::string name;  // the producing op's name, or the graph input's name
  Layout layout;
  int64_t factor = 1;  // spatial size = factor x the LR input size
};

enum class OpKind {
  Conv, Relu, LeakyRelu, Sigmoid, PixelShuffle, Resize, AvgPool, ChannelAffine, Add, Mul, Concat, Sample, AnyAbsAbove
};
enum class ResizeMode { Nearest, Bilinear, Bicubic };

const char* op_kind_name(OpKind kind);        // "conv", "leaky_relu", ...
const char* resize_mode_name(ResizeMode mode);  // "nearest", "bilinear", "bicubic"

struct Op {
  OpKind kind = OpKind::Conv;
  std::string name;         // unique; for ops with tensors, the module path of its parameters
  std::vector<int> inputs;  // value indices
  int output = -1;          // value index
  // Conv
  torch::Tensor weight, bias;
  int64_t stride = 1, padding = 0, dilation = 1, groups = 1;
  // Conv, ChannelAffine: tensors are the network's parameters (true) or constants (false)
  bool trainable = true;
  // LeakyRelu
  double negative_slope = 0.0;
  // PixelShuffle (upscale), Resize (scale), AvgPool (kernel = stride), Sample (output factor /
  // source factor)
  int64_t factor = 1;
  ResizeMode mode = ResizeMode::Nearest;  // Resize; Sample (Nearest or Bilinear)
  // AnyAbsAbove
  double threshold = 0.0;
  // ChannelAffine
  torch::Tensor scale, shift;

  int64_t kernel_size() const { return weight.defined() ? weight.size(-1) : 0; }
};

// What pruning, inheritance and complexity need to know about an op kind, in one table (the
// ONNX and TorchScript writers and the fused graph keep their own closed switches, so the
// compiler flags a kind they miss).
struct OpTraits {
  // Holds tensors: a Conv its weight and bias, a ChannelAffine its scale and shift (the
  // network's parameters when trainable, else constants). These are the ops pruning narrows.
  bool has_tensors = false;
  // Every output channel reads every input channel (a Conv, through its weight's columns), so
  // narrowing the input narrows the tensors too and ties the input's layer groups to the
  // output's. Otherwise output channel c reads input channel c only (element-wise ops).
  bool mixes_channels = false;
};
OpTraits op_traits(OpKind kind);

// The op's tensor elements (weight + bias, or scale + shift): its parameters when trainable.
int64_t tensor_elements(const Op& op);
// Multiply-accumulates per output pixel: the weight's elements for a Conv, 0 for the rest
// (element-wise work is not counted).
int64_t macs_per_output_pixel(const Op& op);
// L1 magnitude per output channel of an op with tensors: sum |weight row| + |bias| of a Conv,
// |scale| + |shift| of a ChannelAffine.
torch::Tensor output_channel_magnitude(const Op& op);

struct Graph {
  std::vector<Value> values;
  std::vector<Op> ops;  // topological order
  std::vector<std::pair<std::string, int>> inputs;   // "color" [N,3,h,w], "info" when the network uses it
  std::vector<std::pair<std::string, int>> outputs;  // "image", and "geometry" for training graphs

  int input(const std::string& name) const;   // value index; Error when absent
  int output(const std::string& name) const;
  bool has_input(const std::string& name) const;
  bool has_output(const std::string& name) const;
  const Op* find_op(const std::string& name) const;  // nullptr when absent
};

// Writes a graph. Names of ops made inside a Scope are prefixed "scope.". Every method checks
// channel counts and layouts, so a mistake in a network's description fails at build time.
class Builder {
 public:
  class Scope {
   public:
    Scope(Builder& b, const std::string& name, bool from_root);
    ~Scope();
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;

   private:
    Builder& builder_;
    std::string previous_;
  };

  Scope scope(const std::string& name) { return Scope(*this, name, false); }
  // A scope that ignores the enclosing ones: ops a module writes from inside another module's
  // description (the RIT's HR part, called back from the backbone's reconstruction).
  Scope root_scope(const std::string& name) { return Scope(*this, name, true); }

  int input(const std::string& name, Layout layout, int64_t factor);
  void output(const std::string& name, int value);

  // A conv whose weight is [out, in, k, k]; `out` must have width out. A stride must divide the
  // input's factor (the output's factor is the input's divided by it).
  int conv(const std::string& name, int x, const torch::Tensor& weight, const torch::Tensor& bias, int64_t padding,
           Layout out, bool trainable = true, int64_t stride = 1);
  int relu(int x);
  int leaky_relu(int x, double negative_slope);
  int sigmoid(int x);
  int pixel_shuffle(int x, int64_t factor);
  int resize(int x, int64_t factor, ResizeMode mode);
  int avg_pool(int x, int64_t factor);
  int affine(const std::string& name, int x, const torch::Tensor& scale, const torch::Tensor& shift, bool trainable);
  int add(int a, int b);
  int mul(int a, int b);
  int concat(const std::vector<int>& parts);
  // `offsets` must be a 2-channel fixed value whose factor is a multiple of the source's.
  int sample(int source, int offsets, ResizeMode mode);
  int any_abs_above(int x, double threshold);

  // The graph being written is the training graph (SRNetworkImpl::describe(true)): ops whose
  // train() behaviour differs from eval() (SRPO's bilinear projection) write the training one.
  void set_training(bool training) { training_ = training; }
  bool training() const { return training_; }

  const Value& value(int index) const { return graph_.values.at(index); }
  Graph finish() { return std::move(graph_); }

 private:
  std::string qualified(const std::string& name) const;
  std::string auto_name(OpKind kind) const;
  int push(Op op, Value out);
  Graph graph_;
  std::string prefix_;
  bool training_ = false;
};

// A graph rewritten: `ops[i]` replaces op i (nullopt drops it; it keeps the original value
// indices), and every value index v that ops and outputs refer to reads `alias[v]` instead
// (empty: no aliases). The values left are renumbered in order of first use.
Graph rewrite(const Graph& graph, const std::vector<std::optional<Op>>& ops, const std::vector<int>& alias = {});

// The kernels modules and the interpreter share, so both compute identical bits.
torch::Tensor apply_resize(const torch::Tensor& x, int64_t factor, ResizeMode mode);
torch::Tensor apply_avg_pool(const torch::Tensor& x, int64_t factor);
torch::Tensor apply_affine(const torch::Tensor& x, const torch::Tensor& scale, const torch::Tensor& shift);
torch::Tensor apply_sample(const torch::Tensor& source, const torch::Tensor& offsets, int64_t ratio, ResizeMode mode);
torch::Tensor apply_any_abs_above(const torch::Tensor& x, double threshold);

// The Sample op's grid in grid_sampler's normalized coordinates (align_corners=False):
// grid = offsets (as [N, H, W, 2]) * sample_grid_scale + sample_grid_base, all float32, so every
// runtime that repeats these two operations gets the same bits.
//   sample_grid_base: [1, out_h, out_w, 2], x: ((2j + 1) / r) / source_w - 1 (y likewise), the
//                     normalized source position of output pixel j's centre
//   sample_grid_scale: [2], 2 / source_w and 2 / source_h in float32 (source pixels to normalized units)
torch::Tensor sample_grid_base(int64_t out_h, int64_t out_w, int64_t ratio, int64_t source_h, int64_t source_w);
torch::Tensor sample_grid_scale(int64_t source_h, int64_t source_w);
// grid_sampler's interpolation_mode of a Sample mode (0 bilinear, 1 nearest, 2 bicubic).
int64_t sample_interpolation(ResizeMode mode);

// Called after each op with its index in graph.ops and its output; returns the value the later
// ops see (the output itself, or e.g. a masked copy). Lets callers observe or adjust activations
// (pruning: activation importance, per-sample channel patterns) without another interpreter.
using OpObserver = std::function<torch::Tensor(size_t op_index, const torch::Tensor& output)>;
// Called before each convolution with its index and input; returns what the convolution reads
// (the input itself, or e.g. the input rounded as INT8 would: models/precision.h). Other readers
// of the same value still see it unchanged.
using ConvInputHook = std::function<torch::Tensor(size_t op_index, const torch::Tensor& input)>;

// Executes the graph. `inputs` maps graph input names to tensors; returns every graph output.
// With `op_ms`, also the wall time of each op in milliseconds (indexed like graph.ops).
std::vector<std::pair<std::string, torch::Tensor>> run(
    const Graph& graph, const std::vector<std::pair<std::string, torch::Tensor>>& inputs,
    std::vector<double>* op_ms = nullptr, const OpObserver& observer = {}, const ConvInputHook& conv_input = {});

}  // namespace cgsr::graph
