#pragma once
// Small building blocks shared by the backbones, the RIT block and the geometry head.

#include <torch/nn/modules/conv.h>

#include <cstdint>
#include <string>

#include "models/graph.h"

namespace cgsr {

// LeakyReLU slope of the PAN reference implementation, used by every block that activates.
constexpr double kLeakySlope = 0.2;

// A k x k convolution with zero "same" padding (k odd) and stride 1.
torch::nn::Conv2d make_conv(int64_t in, int64_t out, int64_t kernel, bool bias = true);

// While one is alive, the networks built on this thread may create at most `values` trainable
// parameter values in all: a conv that would exceed it throws cgsr::Error(context, ...) before it
// allocates. load_model builds the network a model file's spec describes with the file's weights
// as the budget, so a spec with absurd widths is an error, not gigabytes of allocation.
class ParameterBudget {
 public:
  ParameterBudget(int64_t values, std::string context);
  ~ParameterBudget();
  ParameterBudget(const ParameterBudget&) = delete;
  ParameterBudget& operator=(const ParameterBudget&) = delete;

  // Takes the parameter values of a conv (weight and bias) from the innermost live budget, if any.
  static void charge_conv(int64_t in, int64_t out, int64_t kernel, int64_t groups, bool bias);
  // Takes `values` parameter values (checked non-negative) from the innermost live budget, if any.
  static void charge(int64_t values);

 private:
  int64_t values_, left_;
  std::string context_;
  ParameterBudget* outer_;
};

// The graph op of a conv made by make_conv; `out` is the layout of its output channels.
int describe_conv(graph::Builder& g, const std::string& name, const torch::nn::Conv2d& conv, int x,
                  graph::Layout out);

// Sets a conv's weight and bias to zero: the output is exactly zero whatever the input.
void zero_conv(torch::nn::Conv2d& conv);

}  // namespace cgsr
