#pragma once
// The one network type every stage uses: a backbone, optionally the RIT block between its
// feature extraction and reconstruction, and optionally the training-only geometry head.
// Built from an ArchSpec; registered module names ("backbone.", "rit.", "geometry.") are the
// keys of model files.
//
//   SRNetwork net(default_spec("pan", 2));
//   auto sr = net->forward(lr_color);                 // [N, 3, 2h, 2w]
//   auto out = net->forward_train(lr_color, info);    // {image, geometry}
//   loss += lambda_r * net->rit_gate().abs().sum();   // the paper's sum ||R_i||
//
// `info` holds the spec's rendering channels (rit.channels, in render_channels.h order, depth in
// rit.depth_encoding) at LR size for rit.source lr, at HR size for every other source; it may be
// undefined without a RIT. Resizes follow align_corners=False (graph.h).

#include <torch/nn/module.h>
#include <torch/types.h>

#include <map>
#include <memory>
#include <string>

#include "models/arch_spec.h"
#include "models/backbone.h"
#include "models/geometry_head.h"
#include "models/graph.h"
#include "models/rit.h"
#include "render_data/batch.h"

namespace cgsr {

struct TrainOutput {
  torch::Tensor image;     // [N, 3, s*h, s*w]
  torch::Tensor geometry;  // [N, C, s*h, s*w] predicted HR rendering information; undefined without head
};

class SRNetworkImpl : public torch::nn::Module {
 public:
  explicit SRNetworkImpl(const ArchSpec& spec);  // resolves and validates the spec

  torch::Tensor forward(const torch::Tensor& lr_color, const torch::Tensor& info = {});
  TrainOutput forward_train(const torch::Tensor& lr_color, const torch::Tensor& info = {});

  // What the network takes from a Batch: its rendering channels at the resolution the spec asks
  // for (undefined without RIT), and the target of the geometry head (the HR channels). The
  // batch's depth must be in depth_encoding() (an Error says so otherwise). A recurrent network
  // (history_out) also takes its output for the frame before, `previous`: with none (the default,
  // so every reader that knows nothing of it runs the frame alone) the channel's validity is 0
  // (render_data/history_channel.h with_previous_output).
  DepthEncoding depth_encoding() const { return spec_.rit.depth_encoding; }
  torch::Tensor info_input(const Batch& batch, const torch::Tensor& previous = {}) const;
  torch::Tensor geometry_target(const Batch& batch) const;

  // The inference graph (graph.h): inputs "color" (+ the RIT's "info" or "info_hr"), output
  // "image", re-parameterizable branches folded (reparameterization.h): the deployed network.
  // With `training`, the graph training differentiates: branches kept, and the geometry head
  // and its output "geometry".
  graph::Graph describe(bool training = false) const;
  // The inference graph before its branches are folded: what a subnet is cut from (subnet.h),
  // since narrowing a branch's inner channels does not commute with folding.
  graph::Graph describe_branches() const;

  // The RIT gate R [C] (a parameter; undefined without RIT).
  torch::Tensor rit_gate() const;

  const ArchSpec& spec() const { return spec_; }
  std::vector<RenderChannel> input_channels() const { return spec_.input_channels(); }
  BackboneImpl& backbone() const { return *backbone_; }
  bool has_rit() const { return !rit_.is_empty(); }
  bool has_geometry_head() const { return !geometry_.is_empty(); }
  RitBlock rit() const { return rit_; }
  GeometryHead geometry_head() const { return geometry_; }

 private:
  void check_inputs(const torch::Tensor& lr_color, const torch::Tensor& info) const;
  void check_depth_encoding(const Batch& batch) const;
  graph::Graph describe_graph(bool training) const;
  Reconstruction run(const torch::Tensor& lr_color, const torch::Tensor& info);
  ArchSpec spec_;
  std::shared_ptr<BackboneImpl> backbone_;
  RitBlock rit_{nullptr};
  GeometryHead geometry_{nullptr};
};
TORCH_MODULE(SRNetwork);

// The named inputs of an SR network's graph: "color", and the RIT's "info" or "info_hr" (whichever
// the graph has) bound to `info`.
std::vector<std::pair<std::string, torch::Tensor>> network_inputs(const graph::Graph& graph,
                                                                  const torch::Tensor& lr_color,
                                                                  const torch::Tensor& info);

// Trainable parameters: all of them, and those of the inference network (its graph: no geometry
// head, re-parameterizable branches folded).
int64_t total_parameter_count(const SRNetworkImpl& net);
int64_t inference_parameter_count(const SRNetworkImpl& net);

}  // namespace cgsr
