#include "models/reparameterization.h"

#include <torch/torch.h>

#include <optional>

#include "core/error.h"

namespace cgsr {
namespace {

torch::Tensor bias_or_zero(const ConvTensors& c) {
  return c.bias.defined() ? c.bias.to(torch::kFloat64) : torch::zeros({c.weight.size(0)}, torch::kFloat64);
}

bool is_plain_conv(const graph::Op& op) {
  return op.kind == graph::OpKind::Conv && op.stride == 1 && op.dilation == 1 && op.groups == 1;
}

struct Branches {
  int expand = -1, spatial = -1, squeeze = -1, skip = -1;  // op indices
};

// The longest common prefix of the names that ends before a '.': the module the branches share.
std::string common_scope(const std::vector<std::string>& names) {
  std::string prefix = names.front();
  for (const auto& n : names) {
    size_t i = 0;
    while (i < prefix.size() && i < n.size() && prefix[i] == n[i]) ++i;
    prefix.resize(i);
  }
  const auto dot = prefix.rfind('.');
  return dot == std::string::npos ? std::string() : prefix.substr(0, dot);
}

}  // namespace

ConvTensors fold_branches(const ConvTensors& expand, const ConvTensors& spatial, const ConvTensors& squeeze,
                          const ConvTensors& skip) {
  const int64_t k = spatial.weight.size(-1);
  CGSR_CHECK(expand.weight.size(-1) == 1 && squeeze.weight.size(-1) == 1 && skip.weight.size(-1) == 1 && k % 2 == 1,
             "fold_branches: expects 1x1, k x k (k odd), 1x1 and a 1x1 skip");
  CGSR_CHECK(spatial.weight.size(1) == expand.weight.size(0) && squeeze.weight.size(1) == spatial.weight.size(0) &&
                 skip.weight.size(0) == squeeze.weight.size(0) && skip.weight.size(1) == expand.weight.size(1),
             "fold_branches: the branches' channel counts do not chain");
  const auto e = expand.weight.to(torch::kFloat64).flatten(1);    // [m, i]
  const auto s = spatial.weight.to(torch::kFloat64);              // [n, m, k, k]
  const auto q = squeeze.weight.to(torch::kFloat64).flatten(1);   // [o, n]
  auto weight = torch::einsum("on,nmhw,mi->oihw", {q, s, e});
  // The expand bias passes every tap of the spatial conv (the padded border included).
  const auto spatial_bias = bias_or_zero(spatial) + s.sum({2, 3}).matmul(bias_or_zero(expand));
  auto bias = q.matmul(spatial_bias) + bias_or_zero(squeeze) + bias_or_zero(skip);
  weight.select(2, k / 2).select(2, k / 2).add_(skip.weight.to(torch::kFloat64).flatten(1));
  const auto type = spatial.weight.scalar_type();
  return {weight.to(type).contiguous(), bias.to(type).contiguous()};
}

graph::Graph fold_branch_convs(const graph::Graph& graph) {
  const auto& ops = graph.ops;
  std::vector<int> producer(graph.values.size(), -1), readers(graph.values.size(), 0);
  for (size_t i = 0; i < ops.size(); ++i) {
    producer[ops[i].output] = static_cast<int>(i);
    for (int v : ops[i].inputs) ++readers[v];
  }
  for (const auto& [name, v] : graph.outputs) readers[v] += 2;  // a graph output is never folded away
  // The op producing `v` when it is a plain conv read by one op only.
  const auto private_conv = [&](int v, int64_t kernel, int64_t padding) -> std::optional<int> {
    const int p = producer[v];
    if (p < 0 || readers[v] != 1 || !is_plain_conv(ops[p])) return std::nullopt;
    if ((kernel > 0 && ops[p].kernel_size() != kernel) || ops[p].padding != padding) return std::nullopt;
    return p;
  };
  const auto match = [&](int chain, int other) -> std::optional<Branches> {
    const auto squeeze = private_conv(chain, 1, 0);
    if (!squeeze) return std::nullopt;
    const auto spatial = private_conv(ops[*squeeze].inputs[0], 0, 0);
    if (!spatial || ops[*spatial].kernel_size() % 2 == 0) return std::nullopt;
    const auto expand = private_conv(ops[*spatial].inputs[0], 1, ops[*spatial].kernel_size() / 2);
    const auto skip = private_conv(other, 1, 0);
    if (!expand || !skip || ops[*expand].inputs[0] != ops[*skip].inputs[0]) return std::nullopt;
    return Branches{*expand, *spatial, *squeeze, *skip};
  };

  std::vector<std::optional<graph::Op>> rewritten(ops.begin(), ops.end());
  bool folded_any = false;
  for (size_t i = 0; i < ops.size(); ++i) {
    if (ops[i].kind != graph::OpKind::Add) continue;
    auto b = match(ops[i].inputs[0], ops[i].inputs[1]);
    if (!b) b = match(ops[i].inputs[1], ops[i].inputs[0]);
    if (!b) continue;
    const auto tensors = [&](int op) { return ConvTensors{ops[op].weight, ops[op].bias}; };
    const auto folded = fold_branches(tensors(b->expand), tensors(b->spatial), tensors(b->squeeze), tensors(b->skip));
    graph::Op conv = ops[b->spatial];
    const std::string scope =
        common_scope({ops[b->expand].name, ops[b->spatial].name, ops[b->squeeze].name, ops[b->skip].name});
    conv.name = scope.empty() ? ops[i].name : scope;
    conv.inputs = {ops[b->expand].inputs[0]};
    conv.output = ops[i].output;
    conv.weight = folded.weight;
    conv.bias = folded.bias;
    conv.padding = ops[b->spatial].kernel_size() / 2;
    conv.trainable = true;  // the deployed network's parameters, though computed from the branches'
    for (int op : {b->expand, b->spatial, b->squeeze, b->skip}) rewritten[op].reset();
    rewritten[i] = std::move(conv);
    folded_any = true;
  }
  return folded_any ? graph::rewrite(graph, rewritten) : graph;
}

}  // namespace cgsr
