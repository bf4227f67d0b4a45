#pragma once
// Structural re-parameterization: a block trained as linear branches runs as one convolution.
//
// A re-parameterizable convolution (SPAN's Conv3XC) trains as
//   y = squeeze_1x1(spatial_kxk(expand_1x1(x))) + skip_1x1(x)
// with the expand conv zero-padding its input by (k-1)/2 and the spatial conv unpadded. Every
// branch is linear, so y is one k x k convolution of x with "same" zero padding: the expand conv's
// bias reaches the padded border (a 1x1 conv of zeros is its bias), exactly as the folded bias
// assumes. Training graphs keep the branches (their tensors are the parameters); inference
// graphs fold them (SRNetworkImpl::describe), so complexity counting, the latency table, the
// fused path and the exporters all see the network that is deployed.

#include <torch/types.h>

#include "models/graph.h"

namespace cgsr {

struct ConvTensors {
  torch::Tensor weight;  // [out, in, k, k]
  torch::Tensor bias;    // [out], or undefined (zero)
};

// The single convolution the branches compute (computed in float64, returned in the weights'
// type). Shapes: expand [m, i, 1, 1], spatial [n, m, k, k], squeeze [o, n, 1, 1], skip [o, i, 1, 1].
ConvTensors fold_branches(const ConvTensors& expand, const ConvTensors& spatial, const ConvTensors& squeeze,
                          const ConvTensors& skip);

// Every Add(squeeze(spatial(expand(x))), skip(x)) of the graph whose intermediate values nothing
// else reads, replaced by one Conv op named after the branches' common scope (e.g.
// "backbone.blocks.0.c1_r") that holds the folded tensors (computed, not the parameters). Other
// ops are copied as they are; a graph without such a pattern comes back unchanged.
graph::Graph fold_branch_convs(const graph::Graph& graph);

}  // namespace cgsr
