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

// The graph op of a conv made by make_conv; `out` is the layout of its output channels.
int describe_conv(graph::Builder& g, const std::string& name, const torch::nn::Conv2d& conv, int x,
                  graph::Layout out);

// Sets a conv's weight and bias to zero: the output is exactly zero whatever the input.
void zero_conv(torch::nn::Conv2d& conv);

}  // namespace cgsr
