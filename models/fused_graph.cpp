#include "models/fused_graph.h"

#include <oneapi/dnnl/dnnl.hpp>
#include <torch/torch.h>

#include <algorithm>
#include <ctime>
#include <functional>
#include <map>
#include <mutex>
#include <sstream>
#include <unordered_map>

#include "core/error.h"
#include "core/tensor_checks.h"
#include "models/sr_network.h"

namespace cgsr {
namespace {

using dnnl::memory;
using Dims = memory::dims;
using graph::Op;
using graph::OpKind;
constexpr auto kF32 = memory::data_type::f32;
constexpr auto kS8 = memory::data_type::s8;

const char* type_name(memory::data_type t) {
  switch (t) {
    case memory::data_type::bf16: return "bf16";
    case memory::data_type::s8: return "int8";
    default: return "fp32";
  }
}

std::string dims_string(const Dims& d) {
  std::string s = "[";
  for (size_t i = 0; i < d.size(); ++i) s += (i ? ", " : "") + std::to_string(d[i]);
  return s + "]";
}

// oneDNN's reference kernels are correct but scalar: a fused chain that only they can run is
// not worth it.
bool is_reference(const std::string& impl) { return impl.rfind("ref", 0) == 0; }

bool is_activation(OpKind k) { return k == OpKind::Relu || k == OpKind::LeakyRelu || k == OpKind::Sigmoid; }
bool is_binary(OpKind k) { return k == OpKind::Add || k == OpKind::Mul; }

std::pair<dnnl::algorithm, float> activation(const Op& op) {
  switch (op.kind) {
    case OpKind::Relu: return {dnnl::algorithm::eltwise_relu, 0.f};
    case OpKind::LeakyRelu: return {dnnl::algorithm::eltwise_relu, static_cast<float>(op.negative_slope)};
    case OpKind::Sigmoid: return {dnnl::algorithm::eltwise_logistic, 0.f};
    default: break;
  }
  CGSR_CHECK(false, std::string("fused graph: ") + op_kind_name(op.kind) + " is not an activation");
}

dnnl::algorithm binary_algorithm(OpKind k) {
  return k == OpKind::Add ? dnnl::algorithm::binary_add : dnnl::algorithm::binary_mul;
}

torch::Tensor own(const torch::Tensor& t) {
  return t.defined() ? t.detach().to(torch::kFloat).contiguous().clone() : t;
}

void* data(const torch::Tensor& t) { return const_cast<void*>(t.data_ptr()); }

std::vector<float> as_vector(const torch::Tensor& t) {
  const torch::Tensor c = t.to(torch::kFloat).contiguous();
  return {c.data_ptr<float>(), c.data_ptr<float>() + c.numel()};
}

// Per-channel tensors ([C]) as the broadcast operand of a binary op or post-op.
memory::desc channel_md(int64_t c) { return memory::desc({1, c, 1, 1}, kF32, memory::format_tag::nchw); }

// The same kernels as graph::run, for the ops oneDNN has nothing for (bicubic resizing).
torch::Tensor torch_kernel(const Op& op, const std::vector<torch::Tensor>& x) {
  switch (op.kind) {
    case OpKind::Conv: return torch::conv2d(x[0], op.weight, op.bias, op.stride, op.padding, op.dilation, op.groups);
    case OpKind::Relu: return torch::relu(x[0]);
    case OpKind::LeakyRelu: return torch::leaky_relu(x[0], op.negative_slope);
    case OpKind::Sigmoid: return torch::sigmoid(x[0]);
    case OpKind::PixelShuffle: return torch::pixel_shuffle(x[0], op.factor);
    case OpKind::Resize: return graph::apply_resize(x[0], op.factor, op.mode);
    case OpKind::AvgPool: return graph::apply_avg_pool(x[0], op.factor);
    case OpKind::ChannelAffine: return graph::apply_affine(x[0], op.scale, op.shift);
    case OpKind::Add: return x[0] + x[1];
    case OpKind::Mul: return x[0] * x[1];
    case OpKind::Concat: return torch::cat(x, 1);
    case OpKind::Sample: return graph::apply_sample(x[0], x[1], op.factor, op.mode);
    case OpKind::AnyAbsAbove: return graph::apply_any_abs_above(x[0], op.threshold);
  }
  CGSR_CHECK(false, "fused graph: unknown op kind");
}

// A primitive and its arguments. Arguments that are graph values are bound to their buffers
// once the plan has placed them; weights and other constants are bound at creation.
struct Call {
  struct ValueArg {
    int arg;
    int value;
    memory::desc view;  // zero: the value's own descriptor (a pixel shuffle reads another view)
  };
  dnnl::primitive primitive;
  std::vector<ValueArg> values;
  std::unordered_map<int, memory> args;
  memory::desc scratchpad;
  std::vector<torch::Tensor> constants;  // tensors `args` point into that only this call owns
};

template <class PrimitiveDesc>
memory::desc scratchpad_of(const PrimitiveDesc& pd) {
  return pd.scratchpad_desc();
}

// ---- implementation choice ---------------------------------------------------------------------
// oneDNN's first choice for a convolution is not always its fastest at these widths: on AVX-512
// with nhwc it picks the brgemm kernels, which measured up to 1.7x slower than its direct jit
// kernels for 20..40 channels (and faster for others). So each distinct convolution problem
// times every non-reference implementation once and keeps the fastest. The timing runs on one
// thread and counts that thread's CPU time: on a shared machine, wall time of a parallel run
// mostly measures who else was scheduled.

std::string post_ops_key(const dnnl::post_ops& post) {
  std::string key;
  for (int i = 0; i < post.len(); ++i) {
    if (post.kind(i) == dnnl::primitive::kind::sum) {
      key += " sum";
    } else if (post.kind(i) == dnnl::primitive::kind::eltwise) {
      float scale, alpha, beta;
      dnnl::algorithm algorithm;
      post.get_params_eltwise(i, scale, algorithm, alpha, beta);
      key += " eltwise" + std::to_string(static_cast<int>(algorithm)) + ":" + std::to_string(alpha);
    } else {
      dnnl::algorithm algorithm;
      memory::desc operand;
      post.get_params_binary(i, algorithm, operand);
      key += " binary" + std::to_string(static_cast<int>(algorithm)) + dims_string(operand.dims());
    }
  }
  return key;
}

double thread_cpu_ms(const std::function<void()>& f) {
  const auto now = [] {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return t.tv_sec * 1e3 + t.tv_nsec / 1e6;
  };
  const double start = now();
  f();
  return now() - start;
}

void fill(const memory& m, float value) {
  auto* p = static_cast<float*>(m.get_data_handle());
  std::fill(p, p + m.get_desc().get_size() / sizeof(float), value);
}

// oneDNN sizes its work split when a primitive descriptor is made: descriptors made inside this
// scope run on the calling thread alone.
class SingleThread {
 public:
  SingleThread() : threads_(torch::get_num_threads()) { torch::set_num_threads(1); }
  ~SingleThread() { torch::set_num_threads(threads_); }
  SingleThread(const SingleThread&) = delete;
  SingleThread& operator=(const SingleThread&) = delete;

 private:
  int threads_;
};

// The implementation to use for the convolution `desc` with `attr`, among those behind `pd`
// (oneDNN's first choice); `operands` are the descriptors of its post-op operands by argument
// and `key` names the problem.
dnnl::convolution_forward::primitive_desc fastest_convolution(const dnnl::convolution_forward::desc& desc,
                                                              const dnnl::primitive_attr& attr,
                                                              const dnnl::convolution_forward::primitive_desc& pd,
                                                              const std::vector<std::pair<int, memory::desc>>& operands,
                                                              const std::string& key, const dnnl::engine& engine,
                                                              dnnl::stream& stream) {
  static std::mutex mutex;
  static std::map<std::string, std::string> chosen;  // problem -> implementation, for the process
  std::vector<dnnl::convolution_forward::primitive_desc> candidates;
  for (auto it = pd;;) {
    if (!is_reference(it.impl_info_str())) candidates.push_back(it);
    if (!it.next_impl()) break;
  }
  const auto named = [&](const std::string& impl) {
    for (const auto& c : candidates)
      if (impl == c.impl_info_str()) return c;
    return pd;
  };
  if (candidates.size() < 2) return pd;
  {
    std::lock_guard<std::mutex> lock(mutex);
    if (auto it = chosen.find(key); it != chosen.end()) return named(it->second);
  }
  std::string best_impl = pd.impl_info_str();
  {
    SingleThread single;
    std::unordered_map<int, memory> shared = {{DNNL_ARG_SRC, memory(pd.src_desc(), engine)},
                                              {DNNL_ARG_DST, memory(pd.dst_desc(), engine)}};
    if (pd.bias_desc()) shared[DNNL_ARG_BIAS] = memory(pd.bias_desc(), engine);
    for (const auto& [arg, md] : operands) shared[arg] = memory(md, engine);
    for (auto& [arg, m] : shared) fill(m, 0.5f);
    struct Trial {
      std::string impl;
      dnnl::convolution_forward primitive;
      std::unordered_map<int, memory> args;
      double best = 0;
    };
    std::vector<Trial> trials;
    dnnl::convolution_forward::primitive_desc one(desc, attr, engine, /*allow_empty=*/true);
    for (bool more = static_cast<bool>(one); more; more = one.next_impl()) {
      const std::string impl = one.impl_info_str();
      if (is_reference(impl) || named(impl).impl_info_str() != impl) continue;
      Trial t{impl, dnnl::convolution_forward(one), shared};
      t.args[DNNL_ARG_WEIGHTS] = memory(one.weights_desc(), engine);
      fill(t.args[DNNL_ARG_WEIGHTS], 0.01f);
      if (one.scratchpad_desc().get_size() > 0) t.args[DNNL_ARG_SCRATCHPAD] = memory(one.scratchpad_desc(), engine);
      trials.push_back(std::move(t));
    }
    // Best of three runs each; after the first, candidates over twice the best so far stop.
    double best = 1e300;
    for (int round = 0; round < 3; ++round)
      for (auto& t : trials) {
        if (round > 0 && t.best > 2 * best) continue;
        const double ms = thread_cpu_ms([&] {
          t.primitive.execute(stream, t.args);
          stream.wait();
        });
        t.best = round == 0 ? ms : std::min(t.best, ms);
        if (t.best < best) {
          best = t.best;
          best_impl = t.impl;
        }
      }
  }
  std::lock_guard<std::mutex> lock(mutex);
  chosen[key] = best_impl;
  return named(best_impl);
}

// LibTorch fallback: the inputs are reordered into dense NCHW tensors, the result back.
struct TorchCall {
  int op = -1;
  std::vector<torch::Tensor> dense;  // one per op input
  std::vector<Call> to_dense;
  memory result;                     // NCHW, its handle set to the kernel's result per run
  Call from_dense;
};

struct PlannedStep {
  FusedGraph::Step info;
  int position = 0;        // index of the last graph op it computes: steps run in this order
  std::vector<int> reads;  // values
  int writes = -1;
  int overwrites = -1;     // a value whose buffer it writes in place (the residual of a sum post-op)
  std::vector<Call> calls;
  std::unique_ptr<TorchCall> torch_call;
};

struct Compiled {
  int64_t n = 0, h = 0, w = 0;
  dnnl::engine engine{dnnl::engine::kind::cpu, 0};
  dnnl::stream stream{engine};
  std::vector<Dims> dims;          // per graph value
  std::vector<memory::desc> mds;   // per graph value in the activation layout (zero: never built)
  std::vector<memory> mems;
  std::vector<torch::Tensor> buffers;
  torch::Tensor scratchpad;
  std::vector<PlannedStep> steps;
  std::vector<FusedGraph::Step> step_infos;
  std::vector<memory> input_user;  // per graph input: the caller's NCHW tensor, handle set per run
  std::vector<Call> input_calls;
  std::vector<memory> output_user;  // per graph output
  std::vector<Call> output_calls;
};

// Builds a plan for one input size: shapes, fusion, primitives, buffers.
class Compiler {
 public:
  Compiler(const graph::Graph& g, const FusedGraph::Options& options, Compiled& plan)
      : g_(g), options_(options), p_(plan) {}

  void compile() {
    infer_shapes();
    find_uses();
    const bool avx512 = (static_cast<int>(dnnl::get_effective_cpu_isa()) & static_cast<int>(dnnl::cpu_isa::avx512_core)) ==
                        static_cast<int>(dnnl::cpu_isa::avx512_core);
    tag_ = options_.layout == FusedGraph::Layout::ChannelsLast ? memory::format_tag::nhwc
           : avx512                                           ? memory::format_tag::nChw16c
                                                              : memory::format_tag::nChw8c;
    virtual_.assign(g_.values.size(), false);
    for (int i = 0; i < static_cast<int>(g_.ops.size()); ++i) {
      const Op& op = g_.ops[i];
      if (op.kind == OpKind::Concat && options_.split_concat && splittable(op)) virtual_[op.output] = true;
    }
    p_.mds.assign(g_.values.size(), memory::desc());
    for (size_t v = 0; v < g_.values.size(); ++v)
      if (!virtual_[v]) p_.mds[v] = memory::desc(p_.dims[v], kF32, tag_);
    choose_precisions();
    done_.assign(g_.ops.size(), false);
    position_of_.assign(g_.ops.size(), -1);
    for (int i = 0; i < static_cast<int>(g_.ops.size()); ++i)
      if (!done_[i] && !(g_.ops[i].kind == OpKind::Concat && virtual_[g_.ops[i].output])) plan_op(i);
    std::stable_sort(p_.steps.begin(), p_.steps.end(),
                     [](const PlannedStep& a, const PlannedStep& b) { return a.position < b.position; });
    place_values();
    bind();
    for (const auto& s : p_.steps) p_.step_infos.push_back(s.info);
  }

 private:
  int64_t width(int v) const { return p_.dims[v][1]; }
  const memory::desc& md(int v) const { return p_.mds[v]; }
  std::string value_name(int v) const {
    return v < static_cast<int>(g_.values.size()) ? g_.values[v].name : value_name(source_of_.at(v));
  }

  // ---- precision ---------------------------------------------------------------------------------
  // Which convolutions compute in the low format (precision.h low_precision_convs).
  void choose_precisions() {
    low_ = options_.precision == Precision::Bf16   ? memory::data_type::bf16
           : options_.precision == Precision::Int8 ? kS8
                                                   : kF32;
    source_of_.assign(g_.values.size(), -1);
    shadow_.assign(g_.values.size(), -1);
    conv_low_ = options_.low_convs.empty() ? low_precision_convs(g_) : options_.low_convs;
    if (conv_low_.size() != g_.ops.size())
      throw Error("fused graph", "low_convs has " + std::to_string(conv_low_.size()) + " entries for " +
                                     std::to_string(g_.ops.size()) + " ops");
    for (size_t i = 0; i < conv_low_.size(); ++i)
      if (conv_low_[i] && g_.ops[i].kind != OpKind::Conv)
        throw Error("fused graph", "low_convs marks " + g_.ops[i].name + ", which is not a convolution");
    if (low_ == kF32) conv_low_.assign(g_.ops.size(), false);
  }

  bool is_low_conv(int op) const { return g_.ops[op].kind == OpKind::Conv && conv_low_[op]; }

  // Whether `value` is stored in the low format when a low-precision convolution writes it: every
  // reader is a low-precision convolution (directly or through a concatenation that is never built).
  bool stored_low(int value) const {
    if (low_ == kF32 || is_output_[value] || uses_[value].empty()) return false;
    for (int u : uses_[value]) {
      const Op& op = g_.ops[u];
      if (op.kind == OpKind::Concat && virtual_[op.output]) {
        for (int c : uses_[op.output])
          if (!is_low_conv(c)) return false;
      } else if (!is_low_conv(u)) {
        return false;
      }
    }
    return true;
  }

  // The INT8 step of a value (or of the value a converted copy was made from).
  float scale(int value) const {
    if (value >= static_cast<int>(g_.values.size())) return scale(source_of_.at(value));
    return int8_scale(options_.calibration.range(g_.values[value].name));
  }

  // `value` in the low format for a convolution at op `position`: the value itself when its
  // writer stored it so, else a copy converted once, by a step placed before that convolution.
  int low_copy(int value, int position) {
    if (md(value).data_type() == low_) return value;
    if (shadow_[value] >= 0) return shadow_[value];
    const int copy = static_cast<int>(p_.dims.size());
    p_.dims.push_back(p_.dims[value]);
    p_.mds.push_back(memory::desc(p_.dims[value], low_, tag_));
    source_of_.push_back(value);
    shadow_.push_back(-1);
    shadow_[value] = copy;
    PlannedStep step;
    step.info = {"convert", {value_name(value)}, "", type_name(low_)};
    dnnl::primitive_attr a = attr();
    if (low_ == kS8) a.set_output_scales(0, {1.f / scale(value)});
    const dnnl::reorder::primitive_desc pd(p_.engine, md(value), p_.engine, md(copy), a);
    add_implementation(step, pd.impl_info_str());
    Call call = make_call<dnnl::reorder::primitive_desc, dnnl::reorder>(pd);
    call.values = {{DNNL_ARG_FROM, value, {}}, {DNNL_ARG_TO, copy, {}}};
    step.calls.push_back(std::move(call));
    step.position = position;
    step.reads = {value};
    step.writes = copy;
    p_.steps.push_back(std::move(step));
    return copy;
  }

  dnnl::primitive_attr attr(const dnnl::post_ops& post = {}) const {
    dnnl::primitive_attr a;
    a.set_scratchpad_mode(dnnl::scratchpad_mode::user);
    a.set_post_ops(post);
    return a;
  }

  void infer_shapes() {
    p_.dims.assign(g_.values.size(), Dims());
    for (const auto& [name, v] : g_.inputs) {
      const int64_t f = g_.values[v].factor;
      p_.dims[v] = {p_.n, graph::layout_width(g_.values[v].layout), p_.h * f, p_.w * f};
    }
    for (const Op& op : g_.ops) {
      const Dims& x = p_.dims[op.inputs[0]];
      Dims y = x;
      const std::string where = "fused graph: op " + op.name;
      switch (op.kind) {
        case OpKind::Conv: {
          CGSR_CHECK(x[1] == op.weight.size(1) * op.groups, where + ": input channels");
          const auto out = [&](int64_t in, int64_t k) {
            return (in + 2 * op.padding - op.dilation * (k - 1) - 1) / op.stride + 1;
          };
          y = {x[0], op.weight.size(0), out(x[2], op.weight.size(2)), out(x[3], op.weight.size(3))};
          break;
        }
        case OpKind::PixelShuffle: {
          const int64_t r = op.factor;
          CGSR_CHECK(x[1] % (r * r) == 0, where + ": channels not divisible by r*r");
          y = {x[0], x[1] / (r * r), x[2] * r, x[3] * r};
          break;
        }
        case OpKind::Resize: y = {x[0], x[1], x[2] * op.factor, x[3] * op.factor}; break;
        case OpKind::AvgPool: y = {x[0], x[1], x[2] / op.factor, x[3] / op.factor}; break;
        case OpKind::Sample: {
          const Dims& offsets = p_.dims[op.inputs[1]];
          CGSR_CHECK(offsets[1] == 2 && offsets[2] == x[2] * op.factor && offsets[3] == x[3] * op.factor,
                     where + ": offsets " + dims_string(offsets) + " do not match the source " + dims_string(x));
          y = {x[0], x[1], offsets[2], offsets[3]};
          break;
        }
        case OpKind::AnyAbsAbove: y[1] = 1; break;
        case OpKind::Add:
        case OpKind::Mul:
          CGSR_CHECK(p_.dims[op.inputs[1]] == x, where + ": operands of different shapes " + dims_string(x) +
                                                     " and " + dims_string(p_.dims[op.inputs[1]]));
          break;
        case OpKind::Concat:
          y[1] = 0;
          for (int in : op.inputs) {
            const Dims& d = p_.dims[in];
            CGSR_CHECK(d[0] == x[0] && d[2] == x[2] && d[3] == x[3], where + ": parts of different sizes");
            y[1] += d[1];
          }
          break;
        default: break;  // element-wise: same shape
      }
      if (y[2] <= 0 || y[3] <= 0)
        throw Error("fused graph", "op " + op.name + " would produce " + dims_string(y) + ": input " +
                                       std::to_string(p_.h) + "x" + std::to_string(p_.w) + " is too small");
      CGSR_CHECK(y[1] == graph::layout_width(g_.values[op.output].layout), where + ": output width");
      p_.dims[op.output] = y;
    }
  }

  void find_uses() {
    uses_.assign(g_.values.size(), {});
    for (int i = 0; i < static_cast<int>(g_.ops.size()); ++i)
      for (int in : g_.ops[i].inputs) uses_[in].push_back(i);
    is_output_.assign(g_.values.size(), false);
    for (const auto& [name, v] : g_.outputs) is_output_[v] = true;
  }

  static bool is_pointwise_conv(const Op& op) {
    return op.kind == OpKind::Conv && op.weight.size(2) == 1 && op.weight.size(3) == 1 && op.stride == 1 &&
           op.padding == 0 && op.groups == 1;
  }

  // A concatenation that only 1x1 convolutions read: conv(cat(a, b)) = conv_a(a) + conv_b(b).
  bool splittable(const Op& concat) const {
    if (is_output_[concat.output] || uses_[concat.output].empty()) return false;
    for (int j : uses_[concat.output])
      if (!is_pointwise_conv(g_.ops[j])) return false;
    return true;
  }

  // The element-wise ops that can follow `value`'s producer as post-ops: each takes the previous
  // result as its only non-constant operand besides values computed elsewhere, and no other op
  // (nor the graph's outputs) sees the intermediate results.
  std::vector<int> fusable_chain(int value) const {
    std::vector<int> chain;
    if (!options_.fuse) return chain;
    int cur = value;
    while (!is_output_[cur] && uses_[cur].size() == 1) {
      if (done_[uses_[cur][0]]) break;  // already in the chain of another op (one operand of a product)
      const Op& next = g_.ops[uses_[cur][0]];
      const bool ok = is_activation(next.kind) || next.kind == OpKind::ChannelAffine ||
                      (is_binary(next.kind) && next.inputs[0] != next.inputs[1] && !virtual_[other(next, cur)]);
      if (!ok) break;
      chain.push_back(uses_[cur][0]);
      cur = next.output;
    }
    return chain;
  }

  static int other(const Op& binary, int operand) {
    return binary.inputs[0] == operand ? binary.inputs[1] : binary.inputs[0];
  }

  // Appends the chain as post-ops (numbered from `index`), with the operands it reads. The op
  // `summed` (an Add whose other operand already is in the destination) becomes a sum post-op.
  void append_chain(const std::vector<int>& chain, int value, dnnl::post_ops& post, int index, Call& call,
                    PlannedStep& step, int summed = -1, bool summed_already = false) {
    for (int j : chain) {
      const Op& op = g_.ops[j];
      if (j == summed) {
        if (!summed_already) {
          post.append_sum(1.f);
          ++index;
        }
      } else if (is_activation(op.kind)) {
        const auto [algorithm, alpha] = activation(op);
        post.append_eltwise(1.f, algorithm, alpha, 0.f);
        ++index;
      } else if (is_binary(op.kind)) {
        const int operand = other(op, value);
        post.append_binary(binary_algorithm(op.kind), md(operand));
        call.values.push_back({DNNL_ARG_ATTR_MULTIPLE_POST_OP(index) | DNNL_ARG_SRC_1, operand, {}});
        step.reads.push_back(operand);
        ++index;
      } else {  // channel affine
        const int64_t c = p_.dims[op.output][1];
        for (const auto& [t, algorithm] : {std::pair{op.scale, dnnl::algorithm::binary_mul},
                                            std::pair{op.shift, dnnl::algorithm::binary_add}}) {
          if (!t.defined()) continue;
          post.append_binary(algorithm, channel_md(c));
          call.args[DNNL_ARG_ATTR_MULTIPLE_POST_OP(index) | DNNL_ARG_SRC_1] = memory(channel_md(c), p_.engine, data(t));
          ++index;
        }
      }
      step.info.ops.push_back(op.name);
      value = op.output;
    }
  }

  int chain_end(int value, const std::vector<int>& chain) const {
    return chain.empty() ? value : g_.ops[chain.back()].output;
  }

  // Plans op i with the longest fusable chain that a non-reference kernel runs, dropping ops from
  // the chain's end until one does; the dropped ops are planned on their own later.
  void plan_op(int i) {
    const Op& op = g_.ops[i];
    if (op.kind == OpKind::Conv || is_binary(op.kind)) {
      const std::vector<int> full = fusable_chain(op.output);
      for (size_t n = full.size() + 1; n-- > 0;) {
        const std::vector<int> chain(full.begin(), full.begin() + static_cast<std::ptrdiff_t>(n));
        for (bool in_place : {true, false}) {
          PlannedStep step;
          committed_md_ = {-1, {}};
          const bool ok =
              op.kind == OpKind::Conv ? plan_conv(i, chain, step, in_place) : !in_place && plan_binary(i, chain, step);
          if (ok && (n == 0 || !is_reference(step.info.implementation))) {
            if (committed_md_.first >= 0) p_.mds[committed_md_.first] = committed_md_.second;
            finish(i, chain, std::move(step));
            return;
          }
        }
      }
      CGSR_CHECK(false, "fused graph: no oneDNN kernel for " + op.name);
    }
    PlannedStep step;
    if (!plan_single(i, step)) plan_torch(i, step);
    finish(i, {}, std::move(step));
  }

  void finish(int i, const std::vector<int>& chain, PlannedStep step) {
    step.position = chain.empty() ? i : chain.back();
    done_[i] = true;
    position_of_[i] = step.position;
    for (int j : chain) {
      done_[j] = true;
      position_of_[j] = step.position;
    }
    step.writes = chain_end(g_.ops[i].output, chain);
    p_.steps.push_back(std::move(step));
  }

  template <class PrimitiveDesc, class Primitive>
  Call make_call(const PrimitiveDesc& pd) {
    Call call;
    call.primitive = Primitive(pd);
    call.scratchpad = pd.scratchpad_desc();
    return call;
  }

  void add_implementation(PlannedStep& step, const std::string& impl) {
    auto& s = step.info.implementation;
    if (s.empty())
      s = impl;
    else if (s.find(impl) == std::string::npos)
      s += "+" + impl;
    // A step is as slow as its slowest kernel: report a reference one first so callers see it.
    if (is_reference(impl) && !is_reference(s)) s = impl + "+" + s;
  }

  // Whether a step ending at `position` may overwrite `value` while `reader` adds it: every other
  // op reading it belongs to an earlier step (ops not planned yet, the step's own convolution
  // and chain included, do not qualify).
  bool overwritable(int value, int reader, int position) const {
    if (is_output_[value] || virtual_[value]) return false;
    for (int u : uses_[value]) {
      if (u == reader) continue;
      if (!done_[u] || position_of_[u] < 0 || position_of_[u] >= position) return false;
    }
    return true;
  }

  // The residual add of a chain that can be a sum post-op into the residual's own buffer (no
  // operand to stream in, and the brgemm kernels take sums but not binary post-ops): {add op,
  // residual value}, or {-1, -1}. Split convolutions sum their parts into the destination, so
  // there only a leading add can be the first thing in it.
  std::pair<int, int> in_place_add(int i, const std::vector<int>& chain, bool split) const {
    int value = g_.ops[i].output;
    for (size_t k = 0; k < chain.size() && (!split || k == 0); ++k) {
      const Op& op = g_.ops[chain[k]];
      if (op.kind == OpKind::Add && overwritable(other(op, value), chain[k], chain.back()))
        return {chain[k], other(op, value)};
      value = op.output;
    }
    return {-1, -1};
  }

  // A convolution, or one per part of a concatenation it reads (summed into the same output).
  bool plan_conv(int i, const std::vector<int>& chain, PlannedStep& step, bool in_place) {
    const Op& op = g_.ops[i];
    struct Part {
      int value;
      int64_t offset;
    };
    std::vector<Part> parts;
    const int x = op.inputs[0];
    step.info.kind = "conv";
    if (virtual_[x]) {
      const Op& concat = g_.ops[producer(x)];
      int64_t offset = 0;
      for (int in : concat.inputs) {
        parts.push_back({in, offset});
        offset += width(in);
      }
      step.info.ops = {op.name, concat.name};
    } else {
      parts.push_back({x, 0});
      step.info.ops = {op.name};
    }
    const int out = chain_end(op.output, chain);
    // A low-precision convolution reads its parts in the low format and writes it when every
    // reader of its result takes it; a wide one computes in float32.
    const bool low = conv_low_[i];
    const memory::data_type type = low ? low_ : kF32;
    const memory::desc out_md(p_.dims[out], low && stored_low(out) ? low_ : kF32, tag_);
    const bool int8 = type == kS8, int8_out = out_md.data_type() == kS8;
    step.info.precision = type_name(type);
    if (in_place && !options_.sum_in_place) return false;
    if (in_place && out_md.data_type() != kF32) return false;  // residuals are float32
    const auto [summed, residual] = in_place ? in_place_add(i, chain, parts.size() > 1) : std::pair{-1, -1};
    if (in_place && summed < 0) return false;
    if (summed >= 0) {
      step.overwrites = residual;
      step.reads.push_back(residual);
    }
    // INT8: the kernel scales its int32 sums to real values (source step x weight step per output
    // channel) before the post-ops, which then compute in float32, and a last linear post-op
    // steps into the destination's int8 units. When the post-ops are only (leaky) ReLUs, which
    // commute with a positive factor, that factor goes into the output scales instead.
    bool homogeneous = true;
    for (int j : chain) homogeneous = homogeneous && (g_.ops[j].kind == OpKind::Relu || g_.ops[j].kind == OpKind::LeakyRelu);
    const float out_step = int8_out ? scale(out) : 1.f;
    const int64_t kh = op.weight.size(2), kw = op.weight.size(3), oc = op.weight.size(0), g = op.groups;
    for (size_t k = 0; k < parts.size(); ++k) {
      const bool last = k + 1 == parts.size();
      const int src = low ? low_copy(parts[k].value, i) : parts[k].value;
      const int64_t ic = width(src);
      const torch::Tensor weight =
          parts.size() == 1 ? op.weight : op.weight.slice(1, parts[k].offset, parts[k].offset + ic).contiguous();
      const bool bias = k == 0 && op.bias.defined();
      const Dims weight_dims = g > 1 ? Dims{g, oc / g, ic / g, kh, kw} : Dims{oc, ic, kh, kw};
      const memory::desc weight_any(weight_dims, type, memory::format_tag::any);
      const memory::desc weight_user(weight_dims, kF32, g > 1 ? memory::format_tag::goihw : memory::format_tag::oihw);
      const memory::desc bias_md = bias ? memory::desc({oc}, kF32, memory::format_tag::x) : memory::desc();
      const bool folded = int8_out && (!last || homogeneous);
      torch::Tensor weight_steps, output_scales;
      if (int8) {
        weight_steps = int8_channel_scales(weight);
        output_scales = weight_steps * scale(src) / (folded ? out_step : 1.f);
      }
      Call call;
      dnnl::post_ops post;
      int index = 0;
      const bool split = parts.size() > 1;
      if (k > 0 || (split && summed >= 0)) {
        post.append_sum(k > 0 && int8_out && !folded ? out_step : 1.f);
        ++index;
      }
      if (last) append_chain(chain, op.output, post, index, call, step, summed, split);
      if (int8_out && !folded) post.append_eltwise(1.f, dnnl::algorithm::eltwise_linear, 1.f / out_step, 0.f);
      dnnl::primitive_attr conv_attr = attr(post);
      if (int8) conv_attr.set_output_scales(1 << 1, as_vector(output_scales));
      const dnnl::convolution_forward::desc desc(
          dnnl::prop_kind::forward_inference, dnnl::algorithm::convolution_direct, md(src), weight_any, bias_md,
          out_md, {op.stride, op.stride}, {op.dilation - 1, op.dilation - 1}, {op.padding, op.padding},
          {op.padding, op.padding});
      dnnl::convolution_forward::primitive_desc pd(desc, conv_attr, p_.engine, /*allow_empty=*/true);
      if (!pd) return false;
      if (options_.tune) {
        std::vector<std::pair<int, memory::desc>> operands;
        for (const auto& a : call.values) operands.emplace_back(a.arg, md(a.value));
        for (const auto& [arg, m] : call.args) operands.emplace_back(arg, m.get_desc());
        const std::string key = "conv " + dims_string(md(src).dims()) + " " + std::to_string(static_cast<int>(tag_)) +
                                " " + type_name(md(src).data_type()) + "->" + type_name(out_md.data_type()) + " w" +
                                dims_string(weight_dims) + " s" + std::to_string(op.stride) + " p" +
                                std::to_string(op.padding) + " d" + std::to_string(op.dilation) +
                                (bias ? " bias" : "") + post_ops_key(post);
        pd = fastest_convolution(desc, conv_attr, pd, operands, key, p_.engine, p_.stream);
      }
      add_implementation(step, pd.impl_info_str());
      Call made = make_call<dnnl::convolution_forward::primitive_desc, dnnl::convolution_forward>(pd);
      made.args = std::move(call.args);
      made.values = std::move(call.values);
      made.constants = std::move(call.constants);
      // The weights are converted and reordered once, here, into the layout the kernel asked
      // for; INT8 weights are rounded to their channel's step.
      memory reordered(pd.weights_desc(), p_.engine);
      memory user(weight_user, p_.engine, data(weight));
      dnnl::primitive_attr to_kernel;
      if (int8) to_kernel.set_output_scales(g > 1 ? (1 << 0) | (1 << 1) : 1 << 0, as_vector(1.f / weight_steps));
      dnnl::reorder(dnnl::reorder::primitive_desc(p_.engine, weight_user, p_.engine, pd.weights_desc(), to_kernel))
          .execute(p_.stream, user, reordered);
      p_.stream.wait();
      made.args[DNNL_ARG_WEIGHTS] = reordered;
      if (bias) {
        // INT8 kernels add the bias to the int32 sums, before the output scales.
        torch::Tensor b = int8 ? (op.bias / (weight_steps * scale(src))).contiguous() : op.bias;
        made.constants.push_back(b);
        made.args[DNNL_ARG_BIAS] = memory(pd.bias_desc(), p_.engine, data(b));
      }
      made.values.push_back({DNNL_ARG_SRC, src, {}});
      made.values.push_back({DNNL_ARG_DST, out, {}});
      step.reads.push_back(src);
      step.calls.push_back(std::move(made));
    }
    committed_md_ = {out, out_md};
    return true;
  }

  bool plan_binary(int i, const std::vector<int>& chain, PlannedStep& step) {
    const Op& op = g_.ops[i];
    step.info.kind = "binary";
    step.info.ops = {op.name};
    const int out = chain_end(op.output, chain);
    Call call;
    dnnl::post_ops post;
    append_chain(chain, op.output, post, 0, call, step);
    const dnnl::binary::desc desc(binary_algorithm(op.kind), md(op.inputs[0]), md(op.inputs[1]), md(out));
    const dnnl::binary::primitive_desc pd(desc, attr(post), p_.engine, /*allow_empty=*/true);
    if (!pd) return false;
    add_implementation(step, pd.impl_info_str());
    Call made = make_call<dnnl::binary::primitive_desc, dnnl::binary>(pd);
    made.args = std::move(call.args);
    made.values = std::move(call.values);
    made.values.push_back({DNNL_ARG_SRC_0, op.inputs[0], {}});
    made.values.push_back({DNNL_ARG_SRC_1, op.inputs[1], {}});
    made.values.push_back({DNNL_ARG_DST, out, {}});
    step.reads.push_back(op.inputs[0]);
    step.reads.push_back(op.inputs[1]);
    step.calls.push_back(std::move(made));
    return true;
  }

  // Every other op as one primitive; false when oneDNN has none (then LibTorch runs it).
  bool plan_single(int i, PlannedStep& step) {
    const Op& op = g_.ops[i];
    const int x = op.inputs[0], y = op.output;
    step.info.ops = {op.name};
    for (int in : op.inputs) step.reads.push_back(in);
    Call call;
    const auto add = [&](auto pd, auto primitive_tag, const char* kind) {
      using Primitive = decltype(primitive_tag);
      add_implementation(step, pd.impl_info_str());
      step.info.kind = kind;
      call = make_call<decltype(pd), Primitive>(pd);
    };
    switch (op.kind) {
      case OpKind::Relu:
      case OpKind::LeakyRelu:
      case OpKind::Sigmoid: {
        const auto [algorithm, alpha] = activation(op);
        const dnnl::eltwise_forward::desc desc(dnnl::prop_kind::forward_inference, algorithm, md(x), alpha, 0.f);
        add(dnnl::eltwise_forward::primitive_desc(desc, attr(), p_.engine), dnnl::eltwise_forward(), "eltwise");
        call.values = {{DNNL_ARG_SRC, x, {}}, {DNNL_ARG_DST, y, {}}};
        break;
      }
      case OpKind::Resize: {
        if (op.mode == graph::ResizeMode::Bicubic) return false;  // oneDNN resamples nearest and linear only
        const auto algorithm = op.mode == graph::ResizeMode::Nearest ? dnnl::algorithm::resampling_nearest
                                                                     : dnnl::algorithm::resampling_linear;
        const dnnl::resampling_forward::desc desc(dnnl::prop_kind::forward_inference, algorithm, md(x), md(y));
        add(dnnl::resampling_forward::primitive_desc(desc, attr(), p_.engine), dnnl::resampling_forward(),
            "resampling");
        call.values = {{DNNL_ARG_SRC, x, {}}, {DNNL_ARG_DST, y, {}}};
        break;
      }
      case OpKind::AvgPool: {
        const int64_t f = op.factor;
        const dnnl::pooling_forward::desc desc(dnnl::prop_kind::forward_inference,
                                               dnnl::algorithm::pooling_avg_exclude_padding, md(x), md(y), {f, f},
                                               {f, f}, {0, 0}, {0, 0});
        add(dnnl::pooling_forward::primitive_desc(desc, attr(), p_.engine), dnnl::pooling_forward(), "pooling");
        call.values = {{DNNL_ARG_SRC, x, {}}, {DNNL_ARG_DST, y, {}}};
        break;
      }
      case OpKind::ChannelAffine: {
        const int64_t c = width(x);
        if (!op.scale.defined() && !op.shift.defined()) {
          add(dnnl::reorder::primitive_desc(p_.engine, md(x), p_.engine, md(y), attr()), dnnl::reorder(), "reorder");
          call.values = {{DNNL_ARG_SRC, x, {}}, {DNNL_ARG_DST, y, {}}};
          break;
        }
        const bool scale = op.scale.defined();
        dnnl::post_ops post;
        if (scale && op.shift.defined()) post.append_binary(dnnl::algorithm::binary_add, channel_md(c));
        const dnnl::binary::desc desc(scale ? dnnl::algorithm::binary_mul : dnnl::algorithm::binary_add, md(x),
                                      channel_md(c), md(y));
        add(dnnl::binary::primitive_desc(desc, attr(post), p_.engine), dnnl::binary(), "binary");
        call.values = {{DNNL_ARG_SRC_0, x, {}}, {DNNL_ARG_DST, y, {}}};
        call.args[DNNL_ARG_SRC_1] = memory(channel_md(c), p_.engine, data(scale ? op.scale : op.shift));
        if (scale && op.shift.defined())
          call.args[DNNL_ARG_ATTR_MULTIPLE_POST_OP(0) | DNNL_ARG_SRC_1] =
              memory(channel_md(c), p_.engine, data(op.shift));
        break;
      }
      case OpKind::Concat: {
        std::vector<memory::desc> parts;
        for (int in : op.inputs) parts.push_back(md(in));
        add(dnnl::concat::primitive_desc(md(y), 1, parts, p_.engine, attr()), dnnl::concat(), "concat");
        for (size_t k = 0; k < op.inputs.size(); ++k)
          call.values.push_back({DNNL_ARG_MULTIPLE_SRC + static_cast<int>(k), op.inputs[k], {}});
        call.values.push_back({DNNL_ARG_DST, y, {}});
        break;
      }
      case OpKind::PixelShuffle: {
        // Channels-last: the shuffle is a reorder between two strided views of the same
        // [N, C, r, r, H, W] index space. Blocked layouts split channels across blocks: LibTorch.
        if (tag_ != memory::format_tag::nhwc) return false;
        const Dims& s = p_.dims[x];
        const int64_t r = op.factor, c = s[1] / (r * r), hh = s[2], ww = s[3];
        const Dims index = {s[0], c, r, r, hh, ww};
        const memory::desc from(index, kF32, Dims{hh * ww * s[1], r * r, r, 1, ww * s[1], s[1]});
        const int64_t row = ww * r * c;
        const memory::desc to(index, kF32, Dims{hh * r * row, 1, row, c, r * row, r * c});
        add(dnnl::reorder::primitive_desc(p_.engine, from, p_.engine, to, attr()), dnnl::reorder(), "reorder");
        call.values = {{DNNL_ARG_FROM, x, from}, {DNNL_ARG_TO, y, to}};
        break;
      }
      // oneDNN has no gather-by-offsets or threshold primitive: LibTorch runs them (the
      // interpreter's kernels, so the fused path computes the same bits).
      case OpKind::Sample:
      case OpKind::AnyAbsAbove: return false;
      case OpKind::Conv:
      case OpKind::Add:
      case OpKind::Mul: CGSR_CHECK(false, "fused graph: planned elsewhere");
    }
    step.calls.push_back(std::move(call));
    return true;
  }

  void plan_torch(int i, PlannedStep& step) {
    const Op& op = g_.ops[i];
    step.info.kind = "torch";
    step.info.implementation = "torch";
    step.info.ops = {op.name};
    step.reads = op.inputs;
    auto t = std::make_unique<TorchCall>();
    t->op = i;
    for (int in : op.inputs) {
      t->dense.push_back(torch::empty(p_.dims[in]));
      const memory::desc nchw(p_.dims[in], kF32, memory::format_tag::nchw);
      Call call = make_call<dnnl::reorder::primitive_desc, dnnl::reorder>(
          dnnl::reorder::primitive_desc(p_.engine, md(in), p_.engine, nchw, attr()));
      call.values = {{DNNL_ARG_FROM, in, {}}};
      call.args[DNNL_ARG_TO] = memory(nchw, p_.engine, data(t->dense.back()));
      t->to_dense.push_back(std::move(call));
    }
    const memory::desc nchw(p_.dims[op.output], kF32, memory::format_tag::nchw);
    t->result = memory(nchw, p_.engine, nullptr);
    t->from_dense = make_call<dnnl::reorder::primitive_desc, dnnl::reorder>(
        dnnl::reorder::primitive_desc(p_.engine, nchw, p_.engine, md(op.output), attr()));
    t->from_dense.args[DNNL_ARG_FROM] = t->result;
    t->from_dense.values = {{DNNL_ARG_TO, op.output, {}}};
    step.torch_call = std::move(t);
  }

  int producer(int value) const {
    for (int i = 0; i < static_cast<int>(g_.ops.size()); ++i)
      if (g_.ops[i].output == value) return i;
    CGSR_CHECK(false, "fused graph: value without producer");
  }

  // Buffers: a value lives from the step writing it to the last step reading it; a freed buffer
  // is reused by the next value that fits (smallest first), so the plan's footprint is that of
  // the widest point of the graph rather than the sum of all activations.
  void place_values() {
    const int steps = static_cast<int>(p_.steps.size());
    const size_t count = p_.dims.size();  // graph values and converted copies
    constexpr int kNever = -3;
    std::vector<int> last(count, -2);
    for (int s = 0; s < steps; ++s)
      for (int v : p_.steps[s].reads) last[v] = std::max(last[v], s);
    for (const auto& [name, v] : g_.outputs) last[v] = steps;
    for (int s = 0; s < steps; ++s) last[p_.steps[s].writes] = std::max(last[p_.steps[s].writes], s);  // unread
    std::vector<int> buffer_of(count, -1);
    std::vector<size_t> sizes;
    std::multimap<size_t, int> free;  // size -> buffer
    const auto allocate = [&](int v) {
      const size_t bytes = md(v).get_size();
      auto it = free.lower_bound(bytes);
      if (it != free.end()) {
        buffer_of[v] = it->second;
        free.erase(it);
      } else {
        buffer_of[v] = static_cast<int>(sizes.size());
        sizes.push_back(bytes);
      }
    };
    const auto release = [&](int s) {
      for (size_t v = 0; v < count; ++v)
        if (buffer_of[v] >= 0 && last[v] == s) free.emplace(sizes[buffer_of[v]], buffer_of[v]);
    };
    for (const auto& [name, v] : g_.inputs) allocate(v);
    release(-2);  // inputs nothing reads
    for (int s = 0; s < steps; ++s) {
      const PlannedStep& step = p_.steps[s];
      if (step.overwrites >= 0) {  // the buffer passes to the result
        buffer_of[step.writes] = buffer_of[step.overwrites];
        last[step.overwrites] = kNever;
      } else {
        allocate(step.writes);
      }
      release(s);
    }
    for (size_t b = 0; b < sizes.size(); ++b)
      p_.buffers.push_back(torch::empty({static_cast<int64_t>((sizes[b] + 3) / 4)}, torch::kFloat));
    p_.mems.assign(count, memory());
    for (size_t v = 0; v < count; ++v)
      if (buffer_of[v] >= 0) p_.mems[v] = memory(md(v), p_.engine, data(p_.buffers[buffer_of[v]]));
    buffer_of_ = std::move(buffer_of);
  }

  void bind_call(Call& call) {
    for (const auto& a : call.values) {
      CGSR_CHECK(buffer_of_[a.value] >= 0, "fused graph: value " + value_name(a.value) + " has no buffer");
      call.args[a.arg] = a.view ? memory(a.view, p_.engine, p_.mems[a.value].get_data_handle()) : p_.mems[a.value];
    }
    scratch_calls_.push_back(&call);
  }

  void bind() {
    for (const auto& [name, v] : g_.inputs) {
      const memory::desc nchw(p_.dims[v], kF32, memory::format_tag::nchw);
      p_.input_user.push_back(memory(nchw, p_.engine, nullptr));
      Call call = make_call<dnnl::reorder::primitive_desc, dnnl::reorder>(
          dnnl::reorder::primitive_desc(p_.engine, nchw, p_.engine, md(v), attr()));
      call.args[DNNL_ARG_FROM] = p_.input_user.back();
      call.values = {{DNNL_ARG_TO, v, {}}};
      p_.input_calls.push_back(std::move(call));
    }
    for (const auto& [name, v] : g_.outputs) {
      const memory::desc nchw(p_.dims[v], kF32, memory::format_tag::nchw);
      p_.output_user.push_back(memory(nchw, p_.engine, nullptr));
      Call call = make_call<dnnl::reorder::primitive_desc, dnnl::reorder>(
          dnnl::reorder::primitive_desc(p_.engine, md(v), p_.engine, nchw, attr()));
      call.args[DNNL_ARG_TO] = p_.output_user.back();
      call.values = {{DNNL_ARG_FROM, v, {}}};
      p_.output_calls.push_back(std::move(call));
    }
    for (auto& c : p_.input_calls) bind_call(c);
    for (auto& c : p_.output_calls) bind_call(c);
    for (auto& s : p_.steps) {
      for (auto& c : s.calls) bind_call(c);
      if (s.torch_call) {
        for (auto& c : s.torch_call->to_dense) bind_call(c);
        bind_call(s.torch_call->from_dense);
      }
    }
    // One scratchpad for all primitives (they run one after another).
    size_t scratch = 0;
    for (const Call* c : scratch_calls_) scratch = std::max(scratch, c->scratchpad.get_size());
    if (scratch == 0) return;
    p_.scratchpad = torch::empty({static_cast<int64_t>((scratch + 3) / 4)}, torch::kFloat);
    for (Call* c : scratch_calls_)
      if (c->scratchpad.get_size() > 0)
        c->args[DNNL_ARG_SCRATCHPAD] = memory(c->scratchpad, p_.engine, data(p_.scratchpad));
  }

  const graph::Graph& g_;
  const FusedGraph::Options& options_;
  Compiled& p_;
  memory::format_tag tag_ = memory::format_tag::nhwc;
  std::vector<std::vector<int>> uses_;
  std::vector<bool> is_output_, virtual_, done_;
  std::vector<int> position_of_;  // per op: position of the step computing it (once planned)
  memory::data_type low_ = kF32;  // the format of low-precision convolutions
  std::vector<bool> conv_low_;    // per op: a convolution computing in low_
  std::vector<int> shadow_;       // per value: its converted copy, or -1
  std::vector<int> source_of_;    // per value: what a converted copy was made from (-1: none)
  std::pair<int, memory::desc> committed_md_{-1, {}};  // a conv plan's destination, applied if the plan is kept
  std::vector<int> buffer_of_;
  std::vector<Call*> scratch_calls_;
};

void execute(Compiled& p, Call& call) { call.primitive.execute(p.stream, call.args); }

}  // namespace

struct FusedGraph::Plan {
  Compiled compiled;
};

FusedGraph::FusedGraph(const graph::Graph& graph) : FusedGraph(graph, Options()) {}

FusedGraph::FusedGraph(const graph::Graph& graph, Options options) : graph_(graph), options_(options) {
  CGSR_CHECK(!graph_.inputs.empty() && !graph_.outputs.empty(), "fused graph: a graph needs inputs and outputs");
  CGSR_CHECK(options_.cached_plans >= 1, "fused graph: cached_plans must be at least 1");
  if (options_.precision == Precision::Int8 && options_.calibration.ranges.empty())
    throw Error("fused graph", "int8 needs a calibration of the graph's activations (calibrate())");
  for (auto& op : graph_.ops) {
    op.weight = own(op.weight);
    op.bias = own(op.bias);
    op.scale = own(op.scale);
    op.shift = own(op.shift);
  }
}

FusedGraph::~FusedGraph() = default;
FusedGraph::FusedGraph(FusedGraph&&) noexcept = default;
FusedGraph& FusedGraph::operator=(FusedGraph&&) noexcept = default;

FusedGraph::Plan& FusedGraph::plan_for(const std::vector<std::pair<std::string, torch::Tensor>>& inputs) {
  // Every input named once, every graph input given, and all of them one LR size.
  for (size_t i = 0; i < inputs.size(); ++i) {
    if (!graph_.has_input(inputs[i].first)) {
      std::string names;
      for (const auto& [n, v] : graph_.inputs) names += (names.empty() ? "" : ", ") + n;
      throw Error("fused graph", "unknown input '" + inputs[i].first + "' (the graph takes: " + names + ")");
    }
    for (size_t j = 0; j < i; ++j)
      if (inputs[j].first == inputs[i].first) throw Error("fused graph", "input '" + inputs[i].first + "' given twice");
  }
  const auto find = [&](const std::string& name) -> const torch::Tensor& {
    for (const auto& [n, t] : inputs)
      if (n == name) return t;
    throw Error("fused graph", "missing input '" + name + "'");
  };
  int64_t n = 0, h = 0, w = 0;
  for (size_t i = 0; i < graph_.inputs.size(); ++i) {
    const auto& [name, v] = graph_.inputs[i];
    const torch::Tensor& t = find(name);
    const std::string context = "fused graph input '" + name + "'";
    const int64_t c = graph::layout_width(graph_.values[v].layout), f = graph_.values[v].factor;
    if (!t.defined()) throw Error(context, "undefined tensor");
    if (t.scalar_type() != torch::kFloat || !t.device().is_cpu())
      throw Error(context, "expected a float32 CPU tensor, got " + std::string(c10::toString(t.scalar_type())) +
                               " on " + t.device().str());
    if (t.dim() != 4 || t.size(1) != c || t.numel() == 0)
      throw Error(context, "expected [N, " + std::to_string(c) + ", H, W], got " + shape_string(t));
    if (i == 0) {
      if (t.size(2) % f != 0 || t.size(3) % f != 0)
        throw Error(context, shape_string(t) + " is not " + std::to_string(f) + "x an input size");
      n = t.size(0);
      h = t.size(2) / f;
      w = t.size(3) / f;
    }
    const std::vector<int64_t> want = {n, c, h * f, w * f};
    if (t.sizes().vec() != want)
      throw Error(context, "expected " + dims_string(want) + " (" + std::to_string(f) + "x the input size " +
                               std::to_string(h) + "x" + std::to_string(w) + "), got " + shape_string(t));
  }
  for (auto it = plans_.begin(); it != plans_.end(); ++it) {
    const Compiled& c = (*it)->compiled;
    if (c.n == n && c.h == h && c.w == w) {
      plans_.splice(plans_.begin(), plans_, it);
      return *plans_.front();
    }
  }
  auto plan = std::make_unique<Plan>();
  plan->compiled.n = n;
  plan->compiled.h = h;
  plan->compiled.w = w;
  Compiler(graph_, options_, plan->compiled).compile();
  plans_.push_front(std::move(plan));
  while (plans_.size() > options_.cached_plans) plans_.pop_back();
  return *plans_.front();
}

std::vector<std::pair<std::string, torch::Tensor>> FusedGraph::run(
    const std::vector<std::pair<std::string, torch::Tensor>>& inputs) {
  torch::NoGradGuard no_grad;
  Compiled& p = plan_for(inputs).compiled;
  std::vector<torch::Tensor> held;  // contiguous inputs, alive until the run ends
  for (size_t i = 0; i < graph_.inputs.size(); ++i) {
    for (const auto& [name, t] : inputs)
      if (name == graph_.inputs[i].first) held.push_back(t.detach().contiguous());
    p.input_user[i].set_data_handle(data(held.back()));
    execute(p, p.input_calls[i]);
  }
  for (auto& step : p.steps) {
    if (!step.torch_call) {
      for (auto& call : step.calls) execute(p, call);
      continue;
    }
    TorchCall& t = *step.torch_call;
    for (auto& call : t.to_dense) execute(p, call);
    p.stream.wait();
    const torch::Tensor y = torch_kernel(graph_.ops[t.op], t.dense).contiguous();
    t.result.set_data_handle(data(y));
    execute(p, t.from_dense);
    p.stream.wait();  // y is released after this scope
  }
  std::vector<std::pair<std::string, torch::Tensor>> out;
  for (size_t i = 0; i < graph_.outputs.size(); ++i) {
    const int v = graph_.outputs[i].second;
    torch::Tensor y = torch::empty(p.dims[v], torch::kFloat);
    p.output_user[i].set_data_handle(data(y));
    execute(p, p.output_calls[i]);
    out.emplace_back(graph_.outputs[i].first, std::move(y));
  }
  p.stream.wait();
  return out;
}

torch::Tensor FusedGraph::run(const torch::Tensor& color, const torch::Tensor& info) {
  if (!graph_.has_output("image")) throw Error("fused graph", "the graph has no output 'image'");
  for (auto& [name, t] : run(network_inputs(graph_, color, info)))
    if (name == "image") return t;
  CGSR_CHECK(false, "fused graph: output 'image' missing");
}

const std::vector<FusedGraph::Step>& FusedGraph::steps() const {
  static const std::vector<Step> none;
  return plans_.empty() ? none : plans_.front()->compiled.step_infos;
}

std::string FusedGraph::plan_string() const {
  std::ostringstream s;
  for (const auto& step : steps()) {
    s << step.kind << " [" << step.implementation << "]";
    for (size_t i = 0; i < step.ops.size(); ++i) s << (i ? " + " : " ") << step.ops[i];
    s << "\n";
  }
  return s.str();
}

}  // namespace cgsr
