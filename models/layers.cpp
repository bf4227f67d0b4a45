#include "models/layers.h"

#include <torch/torch.h>

#include "core/error.h"

namespace cgsr {
namespace {
thread_local ParameterBudget* innermost_budget = nullptr;
}  // namespace

ParameterBudget::ParameterBudget(int64_t values, std::string context)
    : values_(values), left_(values), context_(std::move(context)), outer_(innermost_budget) {
  innermost_budget = this;
}

ParameterBudget::~ParameterBudget() { innermost_budget = outer_; }

void ParameterBudget::charge(int64_t values) {
  ParameterBudget* b = innermost_budget;
  if (!b) return;
  if (values < 0 || values > b->left_)
    throw Error(b->context_, "the spec describes a network of more than " + std::to_string(b->values_) +
                                 " parameter values, far more than the weights stored for it");
  b->left_ -= values;
}

void ParameterBudget::charge_conv(int64_t in, int64_t out, int64_t kernel, int64_t groups, bool bias) {
  if (!innermost_budget) return;
  // out * in/groups * k * k (+ out) without overflow: -1 (always refused) when it does not fit int64.
  int64_t values = bias ? out : 0, weights = 0;
  const bool overflow = groups < 1 || __builtin_mul_overflow(out, in / groups, &weights) ||
                        __builtin_mul_overflow(weights, kernel, &weights) ||
                        __builtin_mul_overflow(weights, kernel, &weights) ||
                        __builtin_add_overflow(values, weights, &values);
  charge(overflow ? -1 : values);
}

torch::nn::Conv2d make_conv(int64_t in, int64_t out, int64_t kernel, bool bias) {
  CGSR_CHECK(kernel % 2 == 1, "make_conv: kernel size must be odd");
  CGSR_CHECK(in > 0 && out > 0, "make_conv: channel counts must be positive");
  ParameterBudget::charge_conv(in, out, kernel, 1, bias);
  return torch::nn::Conv2d(torch::nn::Conv2dOptions(in, out, kernel).padding(kernel / 2).bias(bias));
}

int describe_conv(graph::Builder& g, const std::string& name, const torch::nn::Conv2d& conv, int x,
                  graph::Layout out) {
  return g.conv(name, x, conv->weight, conv->bias, conv->weight.size(-1) / 2, std::move(out));
}

void zero_conv(torch::nn::Conv2d& conv) {
  torch::NoGradGuard no_grad;
  conv->weight.zero_();
  if (conv->bias.defined()) conv->bias.zero_();
}

}  // namespace cgsr
