#include "models/sr_network.h"

#include <torch/torch.h>

#include <algorithm>

#include "core/error.h"
#include "core/tensor_checks.h"
#include "core/text.h"
#include "models/backbone_registry.h"
#include "models/reparameterization.h"
#include "render_data/history_channel.h"

namespace cgsr {

SRNetworkImpl::SRNetworkImpl(const ArchSpec& spec) : spec_(resolve_spec(spec)) {
  backbone_ = register_module("backbone", backbone_registry().get(spec_.backbone).build(spec_));
  if (spec_.rit.enabled) {
    const auto& b = *backbone_;
    rit_ = register_module(
        "rit", RitBlock(spec_.rit, spec_.scale,
                        FusionPoint{b.feature_group(), spec_.group_width(b.feature_group()), b.feature_factor()},
                        spec_.rit.hr_branch() ? FusionPoint{b.hr_fusion_group(), spec_.group_width(b.hr_fusion_group()),
                                                            spec_.scale}
                                              : FusionPoint{}));
  }
  if (spec_.geometry.enabled)
    geometry_ = register_module("geometry", GeometryHead(spec_.group_width(backbone_->hr_feature_group()),
                                                         spec_.geometry.width, spec_.input_channels()));
}

void SRNetworkImpl::check_inputs(const torch::Tensor& lr_color, const torch::Tensor& info) const {
  const std::string context = spec_summary(spec_);
  if (!lr_color.defined() || lr_color.dim() != 4 || lr_color.size(1) != 3)
    throw Error(context, "colour input must be [N, 3, h, w], got " +
                             (lr_color.defined() ? shape_string(lr_color) : std::string("nothing")));
  // LibTorch's own errors for these name a kernel or resize deep inside the backbone.
  if (lr_color.numel() == 0)
    throw Error(context, "colour input " + shape_string(lr_color) + " is empty: nothing to upscale");
  if (!has_rit()) return;
  const int64_t c = spec_.rit.info_width(), f = rit_->info_factor();
  const std::vector<int64_t> want = {lr_color.size(0), c, lr_color.size(2) * f, lr_color.size(3) * f};
  if (!info.defined() || info.sizes().vec() != want)
    throw Error(context, "rendering information (" + join(spec_.rit.channels) + ", " +
                             (f > 1 ? "HR" : "LR") + " size) must be " + shape_string(torch::empty(want)) +
                             ", got " + (info.defined() ? shape_string(info) : std::string("nothing")));
}

Reconstruction SRNetworkImpl::run(const torch::Tensor& lr_color, const torch::Tensor& info) {
  check_inputs(lr_color, info);
  const auto extracted = backbone_->extract(lr_color);
  if (!has_rit()) return backbone_->reconstruct(extracted.features, extracted.skip, {});
  const auto in = rit_->warp_previous_output(info);
  const auto gated = rit_->gate_info(in);
  const auto features = rit_->has_feature_branch() ? rit_->fuse_features(extracted.features, gated) : extracted.features;
  HrFusion at_hr;
  if (rit_->has_hr_branch()) at_hr = [&](const torch::Tensor& hr) { return rit_->fuse_hr(hr, gated); };
  auto recon = backbone_->reconstruct(features, extracted.skip, at_hr);
  // Last, on the image every caller sees (training's loss too), from the ungated input: the skip
  // at the jitter, then the history, then the renderer's exact BSP borders.
  if (rit_->skips_at_jitter()) recon.image = rit_->skip_at_jitter(recon.image, lr_color, in);
  if (rit_->blends_history()) recon.image = rit_->blend_history(recon.image, in);
  if (rit_->composites_bsp()) recon.image = rit_->composite_bsp(recon.image, in);
  return recon;
}

torch::Tensor SRNetworkImpl::forward(const torch::Tensor& lr_color, const torch::Tensor& info) {
  return run(lr_color, info).image;
}

TrainOutput SRNetworkImpl::forward_train(const torch::Tensor& lr_color, const torch::Tensor& info) {
  const auto recon = run(lr_color, info);
  return {recon.image, has_geometry_head() ? geometry_->forward(recon.hr_features) : torch::Tensor()};
}


torch::Tensor SRNetworkImpl::info_input(const Batch& batch, const torch::Tensor& previous) const {
  if (!has_rit()) return {};
  if (batch.scale != spec_.scale)
    throw Error("batch", "scale x" + std::to_string(batch.scale) + " does not match the model's x" +
                             std::to_string(spec_.scale));
  check_depth_encoding(batch);
  const bool hr = spec_.rit.reads_hr();
  const auto info = pick_channels(hr ? batch.hr_info : batch.lr_info, batch.channels, input_channels(),
                                  hr ? "hr_info" : "lr_info", "the model");
  return with_previous_output(info, input_channels(), previous);
}

void SRNetworkImpl::check_depth_encoding(const Batch& batch) const {
  const auto reads = input_channels();
  if (std::find(reads.begin(), reads.end(), RenderChannel::Depth) == reads.end() ||
      batch.depth_encoding == spec_.rit.depth_encoding)
    return;
  throw Error(spec_summary(spec_), std::string("the batch's depth is ") + enum_name(batch.depth_encoding) +
                                       "-encoded, the model reads " + enum_name(spec_.rit.depth_encoding) +
                                       " (build batches with the model's depth_encoding())");
}

torch::Tensor SRNetworkImpl::geometry_target(const Batch& batch) const {
  if (!has_geometry_head()) return {};
  check_depth_encoding(batch);
  return pick_channels(batch.hr_info, batch.channels, input_channels(), "hr_info", "the model");
}

graph::Graph SRNetworkImpl::describe(bool training) const {
  return training ? describe_graph(true) : fold_branch_convs(describe_graph(false));
}

graph::Graph SRNetworkImpl::describe_branches() const { return describe_graph(false); }

graph::Graph SRNetworkImpl::describe_graph(bool training) const {
  graph::Builder g;
  g.set_training(training);
  const int color = g.input("color", graph::fixed_layout("rgb", 3), 1);
  int info = has_rit() ? g.input(rit_->input_name(), info_layout(input_channels()), rit_->info_factor()) : -1;
  if (has_rit() && rit_->reads_previous_output()) {
    auto scope = g.scope("rit");
    info = rit_->describe_warp_previous_output(g, info);
  }
  ExtractedPorts extracted;
  {
    auto scope = g.scope("backbone");
    extracted = backbone_->describe_extract(g, color);
  }
  int features = extracted.features, gated = -1;
  if (has_rit()) {
    auto scope = g.scope("rit");
    gated = rit_->describe_gate(g, info);
    if (rit_->has_feature_branch()) features = rit_->describe_features(g, features, gated);
  }
  HrFusionPort at_hr;
  if (has_rit() && rit_->has_hr_branch())
    at_hr = [&](int hr) {
      auto scope = g.root_scope("rit");
      return rit_->describe_hr(g, hr, gated);
    };
  ReconstructionPorts recon;
  {
    auto scope = g.scope("backbone");
    recon = backbone_->describe_reconstruct(g, features, extracted.skip, at_hr);
  }
  if (has_rit() && rit_->skips_at_jitter()) {
    auto scope = g.scope("rit");
    recon.image = rit_->describe_skip_at_jitter(g, recon.image, color, info);
  }
  if (has_rit() && rit_->blends_history()) {
    auto scope = g.scope("rit");
    recon.image = rit_->describe_blend_history(g, recon.image, info);
  }
  if (has_rit() && rit_->composites_bsp()) {
    auto scope = g.scope("rit");
    recon.image = rit_->describe_composite_bsp(g, recon.image, info);
  }
  g.output("image", recon.image);
  if (training && has_geometry_head()) {
    auto scope = g.scope("geometry");
    g.output("geometry", geometry_->describe(g, recon.hr_features));
  }
  return g.finish();
}

torch::Tensor SRNetworkImpl::rit_gate() const { return has_rit() ? rit_->gate : torch::Tensor(); }

std::vector<std::pair<std::string, torch::Tensor>> network_inputs(const graph::Graph& graph,
                                                                  const torch::Tensor& lr_color,
                                                                  const torch::Tensor& info) {
  std::vector<std::pair<std::string, torch::Tensor>> inputs = {{"color", lr_color}};
  for (const char* name : {"info", "info_hr"})
    if (graph.has_input(name)) inputs.emplace_back(name, info);
  if (info.defined() && inputs.size() == 1)
    throw Error("network inputs", "rendering information given to a network without a RIT block");
  return inputs;
}

int64_t total_parameter_count(const SRNetworkImpl& net) {
  int64_t n = 0;
  for (const auto& p : net.parameters(/*recurse=*/true)) n += p.numel();
  return n;
}

int64_t inference_parameter_count(const SRNetworkImpl& net) {
  int64_t n = 0;
  for (const auto& op : net.describe(false).ops)
    if (op.trainable) n += graph::tensor_elements(op);
  return n;
}

}  // namespace cgsr
