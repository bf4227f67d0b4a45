#include "models/graph.h"

#include <torch/torch.h>

#include <chrono>
#include <map>

#include "core/error.h"
#include "core/tensor_checks.h"

namespace cgsr::graph {

Layout group_layout(const std::string& group, int64_t channels, int64_t repeat) {
  return {Segment{group, channels, repeat, true}};
}

Layout fixed_layout(const std::string& name, int64_t channels) { return {Segment{name, channels, 1, false}}; }

int64_t layout_width(const Layout& layout) {
  int64_t w = 0;
  for (const auto& s : layout) w += s.channels * s.repeat;
  return w;
}

std::string layout_string(const Layout& layout) {
  std::string out;
  for (const auto& s : layout) {
    if (!out.empty()) out += " + ";
    out += s.group + "(" + std::to_string(s.channels) + (s.repeat > 1 ? "x" + std::to_string(s.repeat) : "") + ")";
  }
  return out;
}

const char* op_kind_name(OpKind kind) {
  switch (kind) {
    case OpKind::Conv: return "conv";
    case OpKind::Relu: return "relu";
    case OpKind::LeakyRelu: return "leaky_relu";
    case OpKind::Sigmoid: return "sigmoid";
    case OpKind::PixelShuffle: return "pixel_shuffle";
    case OpKind::Resize: return "resize";
    case OpKind::AvgPool: return "avg_pool";
    case OpKind::ChannelAffine: return "channel_affine";
    case OpKind::Add: return "add";
    case OpKind::Mul: return "mul";
    case OpKind::Concat: return "concat";
    case OpKind::Sample: return "sample";
    case OpKind::AnyAbsAbove: return "any_abs_above";
  }
  return "?";
}

OpTraits op_traits(OpKind kind) {
  switch (kind) {
    case OpKind::Conv: return {/*has_tensors=*/true, /*mixes_channels=*/true};
    case OpKind::ChannelAffine: return {/*has_tensors=*/true, /*mixes_channels=*/false};
    case OpKind::Relu:
    case OpKind::LeakyRelu:
    case OpKind::Sigmoid:
    case OpKind::PixelShuffle:
    case OpKind::Resize:
    case OpKind::AvgPool:
    case OpKind::Add:
    case OpKind::Mul:
    case OpKind::Concat:
    // Output channel c samples source channel c; the offsets are a fixed 2-channel axis.
    case OpKind::Sample:
    // A fixed 1-channel output of a fixed input (the offsets).
    case OpKind::AnyAbsAbove: return {};
  }
  return {};
}

int64_t tensor_elements(const Op& op) {
  int64_t n = 0;
  for (const auto* t : {&op.weight, &op.bias, &op.scale, &op.shift})
    if (t->defined()) n += t->numel();
  return n;
}

int64_t macs_per_output_pixel(const Op& op) { return op.kind == OpKind::Conv ? op.weight.numel() : 0; }

torch::Tensor output_channel_magnitude(const Op& op) {
  CGSR_CHECK(op_traits(op.kind).has_tensors, "output_channel_magnitude: " + op.name + " has no tensors");
  if (op.kind == OpKind::Conv) {
    auto rows = op.weight.abs().sum({1, 2, 3});
    return op.bias.defined() ? rows + op.bias.abs() : rows;
  }
  torch::Tensor t = op.scale.defined() ? op.scale.abs() : torch::zeros({op.shift.numel()});
  return op.shift.defined() ? t + op.shift.abs() : t;
}

const char* resize_mode_name(ResizeMode mode) {
  switch (mode) {
    case ResizeMode::Nearest: return "nearest";
    case ResizeMode::Bilinear: return "bilinear";
    case ResizeMode::Bicubic: return "bicubic";
  }
  return "?";
}

namespace {
int find_named(const std::vector<std::pair<std::string, int>>& list, const std::string& name, const char* what) {
  for (const auto& [n, v] : list)
    if (n == name) return v;
  throw Error("graph", std::string("no ") + what + " named '" + name + "'", ErrorKind::Internal);
}
bool has_named(const std::vector<std::pair<std::string, int>>& list, const std::string& name) {
  for (const auto& [n, v] : list)
    if (n == name) return true;
  return false;
}
}  // namespace

int Graph::input(const std::string& name) const { return find_named(inputs, name, "input"); }
int Graph::output(const std::string& name) const { return find_named(outputs, name, "output"); }
bool Graph::has_input(const std::string& name) const { return has_named(inputs, name); }
bool Graph::has_output(const std::string& name) const { return has_named(outputs, name); }

const Op* Graph::find_op(const std::string& name) const {
  for (const auto& op : ops)
    if (op.name == name) return &op;
  return nullptr;
}

// ---- builder -----------------------------------------------------------------------------------

Builder::Scope::Scope(Builder& b, const std::string& name, bool from_root) : builder_(b), previous_(b.prefix_) {
  b.prefix_ = (from_root ? std::string() : b.prefix_) + name + ".";
}
Builder::Scope::~Scope() { builder_.prefix_ = previous_; }

std::string Builder::qualified(const std::string& name) const { return prefix_ + name; }

std::string Builder::auto_name(OpKind kind) const {
  return prefix_ + op_kind_name(kind) + "_" + std::to_string(graph_.ops.size());
}

int Builder::push(Op op, Value out) {
  for (const auto& existing : graph_.ops)
    CGSR_CHECK(existing.name != op.name, "graph: duplicate op name '" + op.name + "'");
  out.name = op.name;
  graph_.values.push_back(std::move(out));
  op.output = static_cast<int>(graph_.values.size()) - 1;
  graph_.ops.push_back(std::move(op));
  return graph_.ops.back().output;
}

int Builder::input(const std::string& name, Layout layout, int64_t factor) {
  graph_.values.push_back(Value{name, std::move(layout), factor});
  const int v = static_cast<int>(graph_.values.size()) - 1;
  graph_.inputs.emplace_back(name, v);
  return v;
}

void Builder::output(const std::string& name, int value) { graph_.outputs.emplace_back(name, value); }

int Builder::conv(const std::string& name, int x, const torch::Tensor& weight, const torch::Tensor& bias,
                  int64_t padding, Layout out, bool trainable, int64_t stride) {
  const Value& in = value(x);
  const std::string full = qualified(name);
  CGSR_CHECK(stride >= 1 && in.factor % stride == 0,
             "graph: conv " + full + " stride " + std::to_string(stride) + " does not divide its input's factor " +
                 std::to_string(in.factor));
  CGSR_CHECK(weight.dim() == 4, "graph: conv " + full + " weight must be 4-D");
  CGSR_CHECK(weight.size(1) == layout_width(in.layout),
             "graph: conv " + full + " takes " + std::to_string(weight.size(1)) + " channels but its input " +
                 in.name + " has " + layout_string(in.layout));
  CGSR_CHECK(weight.size(0) == layout_width(out),
             "graph: conv " + full + " makes " + std::to_string(weight.size(0)) + " channels, layout says " +
                 layout_string(out));
  CGSR_CHECK(!bias.defined() || bias.numel() == weight.size(0), "graph: conv " + full + " bias size");
  Op op;
  op.kind = OpKind::Conv;
  op.name = full;
  op.inputs = {x};
  op.weight = weight;
  op.bias = bias;
  op.padding = padding;
  op.stride = stride;
  op.trainable = trainable;
  return push(std::move(op), Value{"", std::move(out), in.factor / stride});
}

namespace {
Op unary(OpKind kind, int x) {
  Op op;
  op.kind = kind;
  op.inputs = {x};
  return op;
}
}  // namespace

int Builder::relu(int x) {
  Op op = unary(OpKind::Relu, x);
  op.name = auto_name(op.kind);
  return push(std::move(op), value(x));
}

int Builder::leaky_relu(int x, double negative_slope) {
  Op op = unary(OpKind::LeakyRelu, x);
  op.name = auto_name(op.kind);
  op.negative_slope = negative_slope;
  return push(std::move(op), value(x));
}

int Builder::sigmoid(int x) {
  Op op = unary(OpKind::Sigmoid, x);
  op.name = auto_name(op.kind);
  return push(std::move(op), value(x));
}

int Builder::pixel_shuffle(int x, int64_t factor) {
  Value out = value(x);
  const int64_t r2 = factor * factor;
  for (auto& s : out.layout) {
    CGSR_CHECK(s.repeat % r2 == 0, "graph: pixel shuffle by " + std::to_string(factor) + " of " +
                                       layout_string(value(x).layout) + " splits a channel group");
    s.repeat /= r2;
  }
  out.factor *= factor;
  Op op = unary(OpKind::PixelShuffle, x);
  op.name = auto_name(op.kind);
  op.factor = factor;
  return push(std::move(op), std::move(out));
}

int Builder::resize(int x, int64_t factor, ResizeMode mode) {
  Value out = value(x);
  out.factor *= factor;
  Op op = unary(OpKind::Resize, x);
  op.name = auto_name(op.kind);
  op.factor = factor;
  op.mode = mode;
  return push(std::move(op), std::move(out));
}

int Builder::avg_pool(int x, int64_t factor) {
  Value out = value(x);
  CGSR_CHECK(out.factor % factor == 0, "graph: pooling " + out.name + " below the LR resolution");
  out.factor /= factor;
  Op op = unary(OpKind::AvgPool, x);
  op.name = auto_name(op.kind);
  op.factor = factor;
  return push(std::move(op), std::move(out));
}

int Builder::affine(const std::string& name, int x, const torch::Tensor& scale, const torch::Tensor& shift,
                    bool trainable) {
  const int64_t c = layout_width(value(x).layout);
  CGSR_CHECK(!scale.defined() || scale.numel() == c, "graph: affine " + qualified(name) + " scale size");
  CGSR_CHECK(!shift.defined() || shift.numel() == c, "graph: affine " + qualified(name) + " shift size");
  Op op = unary(OpKind::ChannelAffine, x);
  op.name = qualified(name);
  op.scale = scale;
  op.shift = shift;
  op.trainable = trainable;
  return push(std::move(op), value(x));
}

namespace {
void require_same(const Value& a, const Value& b, const char* what) {
  CGSR_CHECK(a.factor == b.factor && a.layout == b.layout,
             std::string("graph: ") + what + " of " + a.name + " " + layout_string(a.layout) + " and " + b.name + " " +
                 layout_string(b.layout) + " (factors " + std::to_string(a.factor) + ", " +
                 std::to_string(b.factor) + ") needs identical channel groups and sizes");
}
}  // namespace

int Builder::add(int a, int b) {
  require_same(value(a), value(b), "addition");
  Op op;
  op.kind = OpKind::Add;
  op.inputs = {a, b};
  op.name = auto_name(op.kind);
  return push(std::move(op), value(a));
}

int Builder::mul(int a, int b) {
  require_same(value(a), value(b), "product");
  Op op;
  op.kind = OpKind::Mul;
  op.inputs = {a, b};
  op.name = auto_name(op.kind);
  return push(std::move(op), value(a));
}

int Builder::concat(const std::vector<int>& parts) {
  CGSR_CHECK(!parts.empty(), "graph: empty concat");
  Value out = value(parts[0]);
  out.layout.clear();
  for (int p : parts) {
    CGSR_CHECK(value(p).factor == out.factor, "graph: concat of different spatial sizes");
    for (const auto& s : value(p).layout) out.layout.push_back(s);
  }
  Op op;
  op.kind = OpKind::Concat;
  op.inputs = parts;
  op.name = auto_name(op.kind);
  return push(std::move(op), std::move(out));
}

int Builder::sample(int source, int offsets, ResizeMode mode) {
  const Value& src = value(source);
  const Value& off = value(offsets);
  const std::string what = "graph: sampling " + src.name + " at " + off.name;
  CGSR_CHECK(layout_width(off.layout) == 2 && off.layout.size() == 1 && !off.layout[0].prunable,
             what + ": the offsets must be one fixed 2-channel axis (dx, dy), got " + layout_string(off.layout));
  CGSR_CHECK(off.factor % src.factor == 0, what + ": the offsets' factor " + std::to_string(off.factor) +
                                               " is not a multiple of the source's " + std::to_string(src.factor));
  Value out = src;
  out.factor = off.factor;
  Op op;
  op.kind = OpKind::Sample;
  op.inputs = {source, offsets};
  op.name = auto_name(op.kind);
  op.factor = off.factor / src.factor;
  op.mode = mode;
  return push(std::move(op), std::move(out));
}

int Builder::any_abs_above(int x, double threshold) {
  Value out = value(x);
  out.layout = fixed_layout("mask", 1);
  Op op = unary(OpKind::AnyAbsAbove, x);
  op.name = auto_name(op.kind);
  op.threshold = threshold;
  return push(std::move(op), std::move(out));
}

// ---- kernels -----------------------------------------------------------------------------------

torch::Tensor apply_resize(const torch::Tensor& x, int64_t factor, ResizeMode mode) {
  namespace F = torch::nn::functional;
  const std::vector<double> scales = {static_cast<double>(factor), static_cast<double>(factor)};
  auto options = F::InterpolateFuncOptions().scale_factor(scales).recompute_scale_factor(false);
  switch (mode) {
    case ResizeMode::Nearest: return F::interpolate(x, options.mode(torch::kNearest));
    case ResizeMode::Bilinear: return F::interpolate(x, options.mode(torch::kBilinear).align_corners(false));
    case ResizeMode::Bicubic: return F::interpolate(x, options.mode(torch::kBicubic).align_corners(false));
  }
  CGSR_CHECK(false, "unknown resize mode");
}

torch::Tensor apply_avg_pool(const torch::Tensor& x, int64_t factor) {
  return torch::avg_pool2d(x, {factor, factor}, {factor, factor});
}

torch::Tensor apply_affine(const torch::Tensor& x, const torch::Tensor& scale, const torch::Tensor& shift) {
  torch::Tensor y = x;
  if (scale.defined()) y = y * scale.view({1, -1, 1, 1});
  if (shift.defined()) y = y + shift.view({1, -1, 1, 1});
  return y;
}

namespace {
// Normalized source coordinate of the centre of each of n output pixels: ((2j + 1) / r) / size - 1.
torch::Tensor normalized_centres(int64_t n, int64_t ratio, int64_t size) {
  return (torch::arange(n, torch::kFloat) * 2 + 1) / ratio / size - 1;
}
}  // namespace

torch::Tensor sample_grid_base(int64_t out_h, int64_t out_w, int64_t ratio, int64_t source_h, int64_t source_w) {
  const auto x = normalized_centres(out_w, ratio, source_w).view({1, out_w}).expand({out_h, out_w});
  const auto y = normalized_centres(out_h, ratio, source_h).view({out_h, 1}).expand({out_h, out_w});
  return torch::stack({x, y}, -1).unsqueeze(0);
}

torch::Tensor sample_grid_scale(int64_t source_h, int64_t source_w) {
  // float32 division (not double rounded to float), as the exporters divide.
  return torch::full({2}, 2.0f) / torch::tensor({static_cast<float>(source_w), static_cast<float>(source_h)});
}

int64_t sample_interpolation(ResizeMode mode) {
  switch (mode) {
    case ResizeMode::Bilinear: return 0;
    case ResizeMode::Nearest: return 1;
    case ResizeMode::Bicubic: return 2;
  }
  throw Error("sample", "unknown sampling mode " + std::to_string(static_cast<int>(mode)));
}

torch::Tensor apply_sample(const torch::Tensor& source, const torch::Tensor& offsets, int64_t ratio, ResizeMode mode) {
  CGSR_CHECK(source.dim() == 4 && offsets.dim() == 4 && offsets.size(1) == 2 && offsets.size(0) == source.size(0) &&
                 offsets.size(2) == source.size(2) * ratio && offsets.size(3) == source.size(3) * ratio,
             "sample: offsets " + shape_string(offsets) + " must be [N, 2, " + std::to_string(ratio) +
                 " x the height, width] of the source " + shape_string(source));
  const int64_t h = source.size(2), w = source.size(3);
  const auto grid = offsets.permute({0, 2, 3, 1}) * sample_grid_scale(h, w).to(offsets.options()) +
                    sample_grid_base(offsets.size(2), offsets.size(3), ratio, h, w).to(offsets.options());
  return torch::grid_sampler(source, grid, sample_interpolation(mode), /*padding_mode=border*/ 1,
                             /*align_corners=*/false);
}

torch::Tensor apply_any_abs_above(const torch::Tensor& x, double threshold) {
  return (x.abs().amax(1, /*keepdim=*/true) > threshold).to(x.scalar_type());
}

Graph rewrite(const Graph& graph, const std::vector<std::optional<Op>>& ops, const std::vector<int>& alias) {
  CGSR_CHECK(ops.size() == graph.ops.size(), "graph rewrite: one entry per op");
  std::vector<int> index(graph.values.size(), -1);
  Graph out;
  const auto keep_value = [&](int v) {
    if (!alias.empty()) v = alias.at(v);
    if (index[v] < 0) {
      index[v] = static_cast<int>(out.values.size());
      out.values.push_back(graph.values[v]);
    }
    return index[v];
  };
  for (const auto& [name, v] : graph.inputs) out.inputs.emplace_back(name, keep_value(v));
  for (const auto& op : ops) {
    if (!op) continue;
    Op kept = *op;
    for (int& v : kept.inputs) v = keep_value(v);
    kept.output = keep_value(kept.output);
    out.ops.push_back(std::move(kept));
  }
  for (const auto& [name, v] : graph.outputs) out.outputs.emplace_back(name, keep_value(v));
  return out;
}

// ---- interpreter -------------------------------------------------------------------------------

std::vector<std::pair<std::string, torch::Tensor>> run(
    const Graph& graph, const std::vector<std::pair<std::string, torch::Tensor>>& inputs,
    std::vector<double>* op_ms, const OpObserver& observer, const ConvInputHook& conv_input) {
  if (op_ms) op_ms->assign(graph.ops.size(), 0.0);
  std::vector<torch::Tensor> values(graph.values.size());
  for (const auto& [name, v] : graph.inputs) {
    bool found = false;
    for (const auto& [n, t] : inputs)
      if (n == name) {
        const int64_t want = layout_width(graph.values[v].layout);
        if (t.dim() != 4 || t.size(1) != want)
          throw Error("graph input '" + name + "'", "expected [N, " + std::to_string(want) + ", H, W], got " +
                                                         shape_string(t));
        values[v] = t;
        found = true;
      }
    if (!found) throw Error("graph", "missing input '" + name + "'");
  }
  for (size_t index = 0; index < graph.ops.size(); ++index) {
    const Op& op = graph.ops[index];
    const auto start = std::chrono::steady_clock::now();
    const auto& in = [&](size_t i) -> const torch::Tensor& { return values[op.inputs[i]]; };
    torch::Tensor y;
    switch (op.kind) {
      case OpKind::Conv:
        y = torch::conv2d(conv_input ? conv_input(index, in(0)) : in(0), op.weight, op.bias, op.stride, op.padding,
                          op.dilation, op.groups);
        break;
      case OpKind::Relu: y = torch::relu(in(0)); break;
      case OpKind::LeakyRelu: y = torch::leaky_relu(in(0), op.negative_slope); break;
      case OpKind::Sigmoid: y = torch::sigmoid(in(0)); break;
      case OpKind::PixelShuffle: y = torch::pixel_shuffle(in(0), op.factor); break;
      case OpKind::Resize: y = apply_resize(in(0), op.factor, op.mode); break;
      case OpKind::AvgPool: y = apply_avg_pool(in(0), op.factor); break;
      case OpKind::ChannelAffine: y = apply_affine(in(0), op.scale, op.shift); break;
      case OpKind::Add: y = in(0) + in(1); break;
      case OpKind::Mul: y = in(0) * in(1); break;
      case OpKind::Concat: {
        std::vector<torch::Tensor> parts;
        for (size_t i = 0; i < op.inputs.size(); ++i) parts.push_back(in(i));
        y = torch::cat(parts, 1);
        break;
      }
      case OpKind::Sample: y = apply_sample(in(0), in(1), op.factor, op.mode); break;
      case OpKind::AnyAbsAbove: y = apply_any_abs_above(in(0), op.threshold); break;
    }
    values[op.output] = observer ? observer(index, y) : y;
    if (op_ms)
      (*op_ms)[index] = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  }
  std::vector<std::pair<std::string, torch::Tensor>> out;
  for (const auto& [name, v] : graph.outputs) out.emplace_back(name, values[v]);
  return out;
}

}  // namespace cgsr::graph
