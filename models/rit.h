#pragma once
// The rendering information transform (RIT) block of CGSR (Fig. 3 of the paper): turns the
// chosen rendering channels into features and fuses them into the backbone. `rit.source` says
// where the information comes from and where it joins:
//
//   lr            info [N, C, h, w] (graph input "info"), joins the feature map
//   hr_pooled     info [N, C, s*h, s*w] ("info_hr") averaged over s x s windows to LR first
//   hr_unshuffle  info at HR, space-to-depth onto the LR grid (C*s*s channels, lossless), then the
//                 3x3 conv; written as the equivalent 3s x 3s conv with stride s and padding s
//                 (same weights, same parameters, any runtime runs it)
//   hr_fuse       info at HR feeds a branch at the backbone's HR features (after its last
//                 upsampling, before its last HR convolutions): what the colour cannot tell is
//                 where geometry edges are at the output resolution
//   hr_unshuffle+hr_fuse  both, from the one HR input (multi-scale)
//
// Each part is gate -> conv -> LeakyReLU 0.2 -> fusion:
//   gate: x[c] * R[c], the regularization layer, shared by both parts; an L1 penalty on R lets
//         training switch off channels a scene does not need, which can then be left out
//   feature part: conv (C -> width, layer group "rit"), bilinear upsampling when the feature
//         map is at HR (SRCNN); fusion into the feature map
//   HR part: conv 3x3 (C -> hr_width, layer group "rit_hr"); fusion into the HR features
//   fusion concat: features + conv1x1(cat(features, rit)); add: features + conv1x1(rit)
//
// Every fusion conv starts at zero, so a network with a fresh RIT computes exactly what its
// backbone computes (x + 0 == x), and training starts from the pretrained behaviour.
//
// rit.bsp_composite: the network's image is composited with the bsp channel read from the raw
// (ungated) HR input: out = (1 - m) * net + m * bsp_rgb, m the channel's coverage (1 on the pixels
// whose centre lies in an LR border pixel, where the renderer resolved the edge into BSP leaves).
// The networks learn little of copying the leaves (docs/results/bsp_rit.md), so they are given
// them; training's loss is on the composite, so the network learns the other pixels. Written
// with fixed 0/1 1x1 convs that pick the colour and the coverage (broadcast to 3 channels) out of
// the info input, a ChannelAffine for 1 - m, Mul and Add: every runtime runs it, and as m is 0 or
// 1 the result is exactly bsp_rgb or net (0 * x + y == y), not net + (bsp - net) rounded.
//
// history_out: the network's own previous output, passed back in by the runner, is warped to this
// frame first (graph Sample at the channel's motion, bilinear or, with rit.history_warp bicubic,
// bicubic; border padding) and zeroed where the channel's validity is 0; every part below reads
// that instead of the raw channel. Written with fixed 0/1 1x1 convs, Sample, Mul and Add: the
// exported file warps it too, and the state it takes is the previous output as the network
// returned it (docs/temporal.md).
//
// rit.history_blend: the image blended with the history channel's samples (render_data/
// history_channel.h; history_out's warped output instead when the RIT reads it), read from the
// HR input: out = net + w * (hist_rgb - net), with
// w = sigmoid(conv3x3(cat(net, info))) * recency. Recency is 0 where no frame left a sample, so the
// output there is the network's exactly; elsewhere the conv (layer "blend", 3 outputs, starting at
// weight 0 and bias -4: w under 0.02) learns how far to trust a sample from its age, the
// G-buffers and its disagreement with the network. A network given the samples as input learned
// nothing from them (docs/results/history.md); here using one is a single weight away.
//
// rit.skip_at_jitter: PAN adds the LR image, bilinearly upsampled, to its output; in a jittered
// frame that reads each output pixel up to half an LR pixel from where its content sits. The
// option swaps that skip for the same interpolation at the frame's jitter (the jitter channel of
// the raw HR input): out = net + (sample(lr, jitter) - bilinear(lr)), where sample reads the LR
// image at (j + 0.5) / s - 0.5 + jitter (graph Sample, bilinear), the unjittered output grid.
// Without jitter (0) both interpolations are the same and the output is the network's. No
// parameters: fixed 0/1 1x1 convs pick the jitter out of the info input.
//
// rit.residual_at_jitter (with skip_at_jitter): the backbone reads the jittered LR frame as if it
// were aligned, so the detail it adds over its skip sits s * jitter HR pixels from where it
// belongs. The residual is resampled there too: out = sample_hr(net - bilinear(lr), s * jitter) +
// sample(lr, jitter), bilinear at the output resolution (border padding). No parameters.

#include <torch/nn/module.h>
#include <torch/nn/modules/conv.h>
#include <torch/types.h>

#include "models/arch_spec.h"
#include "models/graph.h"

namespace cgsr {

// The layout of a rendering-information tensor: one fixed segment per named channel.
graph::Layout info_layout(const std::vector<RenderChannel>& channels);

// Where a part of the RIT joins the backbone: the layer group, width and spatial factor
// (relative to LR) of the features there.
struct FusionPoint {
  std::string group;
  int64_t channels = 0;
  int64_t factor = 1;
};

class RitBlockImpl : public torch::nn::Module {
 public:
  RitBlockImpl(const RitSpec& rit, int scale, FusionPoint features, FusionPoint hr_features);

  // history_out (render_channels.h): the information with that channel's previous output warped to
  // this frame through its motion (bilinear, graph Sample) and zeroed where it is not valid, and
  // its motion zeroed (the warp's alone); what every other part reads. `info` itself without it.
  bool reads_previous_output() const { return previous_keep_.defined(); }
  torch::Tensor warp_previous_output(const torch::Tensor& info) const;
  int describe_warp_previous_output(graph::Builder& g, int info) const;
  // The gated information both parts read (hr_pooled: pooled first, as the gate always was),
  // narrowed to rit.feature_channels when set.
  torch::Tensor gate_info(const torch::Tensor& info) const;
  torch::Tensor fuse_features(const torch::Tensor& features, const torch::Tensor& gated);
  torch::Tensor fuse_hr(const torch::Tensor& hr_features, const torch::Tensor& gated);
  // Graph mirrors; `info` is the graph input holding the rendering information.
  int describe_gate(graph::Builder& g, int info) const;
  int describe_features(graph::Builder& g, int features, int gated) const;
  int describe_hr(graph::Builder& g, int hr_features, int gated) const;
  // rit.bsp_composite: the image composited with the bsp channel of `info` (the raw HR input).
  bool composites_bsp() const { return bsp_color_.defined(); }
  torch::Tensor composite_bsp(const torch::Tensor& image, const torch::Tensor& info) const;
  int describe_composite_bsp(graph::Builder& g, int image, int info) const;
  // rit.history_blend: the image blended with the history channel of `info` (the raw HR input).
  bool blends_history() const { return !blend.is_empty(); }
  torch::Tensor blend_history(const torch::Tensor& image, const torch::Tensor& info);
  int describe_blend_history(graph::Builder& g, int image, int info) const;
  // rit.skip_at_jitter: the image with its bilinear skip of `lr_color` moved to the jitter of `info`
  // (with residual_at_jitter, the rest of the image too).
  bool skips_at_jitter() const { return jitter_offsets_.defined(); }
  torch::Tensor skip_at_jitter(const torch::Tensor& image, const torch::Tensor& lr_color, const torch::Tensor& info) const;
  int describe_skip_at_jitter(graph::Builder& g, int image, int lr_color, int info) const;

  bool has_feature_branch() const { return !conv.is_empty(); }
  bool has_hr_branch() const { return !hr_conv.is_empty(); }
  // The graph input's name and resolution relative to LR: "info" and 1 for lr, else "info_hr"
  // and the scale.
  const char* input_name() const { return info_factor_ > 1 ? "info_hr" : "info"; }
  int64_t info_factor() const { return info_factor_; }

  torch::Tensor gate;  // [C], R_i of the paper, initialized to 1
  torch::nn::Conv2d conv{nullptr}, fuse{nullptr};        // the feature part
  torch::nn::Conv2d hr_conv{nullptr}, hr_fuse{nullptr};  // the HR part
  torch::nn::Conv2d blend{nullptr};                      // history_blend: the weight's conv

 private:
  // features + fusion(cat(features, x)) or features + fusion(x), and its graph mirror.
  torch::Tensor join(const torch::Tensor& features, const torch::Tensor& x, torch::nn::Conv2d& fusion);
  int describe_join(graph::Builder& g, const std::string& name, const torch::nn::Conv2d& fusion, int features,
                    int x) const;

  bool concat_;
  int64_t info_factor_;      // 1 (lr) or the scale
  int64_t pool_factor_;      // hr_pooled: the scale
  int64_t stride_;           // hr_unshuffle: the scale
  int64_t upsample_factor_;  // the feature map's factor
  // bsp_composite: constants (no parameters, not in model files), [3, C, 1, 1] 0/1 selections of
  // the bsp colour and of its coverage for each of R, G, B; and 1 - m as scale -1, shift 1.
  torch::Tensor bsp_color_, bsp_coverage_, complement_scale_, complement_shift_;
  // history_blend: constants, [3, C, 1, 1] selections of the history colour and of its recency
  // (broadcast to R, G, B); and -x as scale -1, shift 0.
  torch::Tensor history_color_, history_recency_, negate_scale_, negate_shift_;
  // skip_at_jitter: a constant [2, C, 1, 1] selection of the jitter (x, y); residual_at_jitter:
  // the same times the scale (the jitter in HR pixels), else undefined.
  torch::Tensor jitter_offsets_, hr_jitter_offsets_;
  // history_out: constants, [3, C, 1, 1] selections of the previous colour and of its validity
  // (broadcast), [2, C, 1, 1] of its motion; [C, C, 1, 1] the identity but for the colour and the
  // motion, and [C, 3, 1, 1] the warped colour back into the colour's place.
  torch::Tensor previous_color_, previous_validity_, previous_motion_, previous_keep_, previous_embed_;
  graph::ResizeMode previous_warp_ = graph::ResizeMode::Bilinear;  // rit.history_warp
  // rit.feature_channels: a constant [C', C, 1, 1] 0/1 selection of the channels the convolutions
  // read, and their layout; undefined when they read all.
  torch::Tensor feature_select_;
  graph::Layout feature_layout_;
  int64_t scale_;
};
TORCH_MODULE(RitBlock);

}  // namespace cgsr
