#pragma once
// The interface every SR backbone implements. CGSR splits a backbone into feature extraction
// and reconstruction and inserts the rendering information transform (rit.h) between them, so
// a backbone exposes the two parts separately, plus a graph description of each (graph.h) that
// mirrors its forward op for op.
//
// A backbone is built from an ArchSpec: the width of each of its layer groups and its number of
// blocks come from the spec, so one class covers the published network and every shrunk child.

#include <torch/nn/module.h>
#include <torch/types.h>

#include <cstdint>
#include <functional>
#include <string>

#include "models/arch_spec.h"
#include "models/graph.h"

namespace cgsr {

struct ExtractedFeatures {
  torch::Tensor features;  // [N, F, f*h, f*w] at the insertion point (f = feature_factor())
  torch::Tensor skip;      // what the reconstruction needs besides the features (may be undefined)
};

struct Reconstruction {
  torch::Tensor image;        // [N, 3, s*h, s*w]
  torch::Tensor hr_features;  // the input of the last conv: what the geometry head reads
};

struct ExtractedPorts {
  int features = -1;  // graph value indices
  int skip = -1;
};

struct ReconstructionPorts {
  int image = -1;
  int hr_features = -1;
};

// The HR fusion point (the RIT's HR part, rit.h): reconstruct() passes the features it has after
// its last upsampling, before its last HR convolutions, through this function and goes on with
// what it returns; an empty function leaves them alone. HrFusionPort is the graph mirror.
using HrFusion = std::function<torch::Tensor(const torch::Tensor&)>;
using HrFusionPort = std::function<int(int)>;

class BackboneImpl : public torch::nn::Module {
 public:
  ~BackboneImpl() override = default;

  // lr_color: [N, 3, h, w] RGB in [0,1], whatever the spec's `colors`.
  virtual ExtractedFeatures extract(const torch::Tensor& lr_color) = 0;
  virtual Reconstruction reconstruct(const torch::Tensor& features, const torch::Tensor& skip,
                                     const HrFusion& at_hr) = 0;

  // Graph mirrors of extract() and reconstruct(); op names are module paths relative to the
  // backbone (the caller opens the "backbone" scope).
  virtual ExtractedPorts describe_extract(graph::Builder& g, int color) const = 0;
  virtual ReconstructionPorts describe_reconstruct(graph::Builder& g, int features, int skip,
                                                   const HrFusionPort& at_hr) const = 0;

  // The layer group and spatial factor (relative to LR) of the features at the insertion point.
  virtual std::string feature_group() const = 0;
  virtual int64_t feature_factor() const = 0;
  // The layer group of Reconstruction::hr_features.
  virtual std::string hr_feature_group() const = 0;
  // The layer group of the features at the HR fusion point.
  virtual std::string hr_fusion_group() const = 0;
};

}  // namespace cgsr
