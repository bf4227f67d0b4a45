#include "search/subnet_evaluator.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/runtime.h"
#include "models/complexity.h"
#include "models/graph.h"
#include "render_data/edges.h"
#include "render_data/patch_sampler.h"

namespace cgsr {

config::Schema<ValidationCropOptions> validation_crop_schema() {
  config::Schema<ValidationCropOptions> s;
  s.field("frames", &ValidationCropOptions::frames, "validation frames the crops come from (0: all)").at_least(0);
  s.field("crops_per_frame", &ValidationCropOptions::crops_per_frame, "crops per frame").range(1, 1000);
  s.field("size", &ValidationCropOptions::size, "LR pixels scored per crop side").range(4, 4096);
  s.field("margin", &ValidationCropOptions::margin, "LR pixels run around a crop and cut off").range(0, 64);
  return s;
}

InferenceEvaluator::InferenceEvaluator(SRNetwork network, const Dataset& data, const ValidationCropOptions& crops,
                                       LatencyTable table)
    : network_(std::move(network)), table_(std::move(table)) {
  network_->eval();
  const int scale = network_->spec().scale;
  std::vector<int> frames = spread_frames(data.frames(Split::Val), crops.frames);
  if (frames.empty()) frames = spread_frames(data.frames(Split::Train), std::max(1, crops.frames));
  if (frames.empty()) throw Error(data.info().root.string(), "no frames to score subnets on");
  const auto [lr_res, hr_res] = resolution_pair(data, scale);
  const auto& hr_channels = channels_at(data.info(), hr_res);
  const bool edges = std::find(hr_channels.begin(), hr_channels.end(), RenderChannel::Edge) != hr_channels.end();
  std::vector<RenderChannel> channels = network_->input_channels();
  if (edges && std::find(channels.begin(), channels.end(), RenderChannel::Edge) == channels.end())
    channels.push_back(RenderChannel::Edge);

  auto rng = make_rng("subnet-evaluator-crops");
  const int side = crops.size + 2 * crops.margin;
  std::vector<torch::Tensor> lr, info, hr, mask;
  for (int frame : frames) {
    const Batch b = frame_batch(data, frame, scale, channels, network_->depth_encoding());
    const int64_t h = b.lr_color.size(2), w = b.lr_color.size(3);
    if (h < side || w < side)
      throw Error(data.info().root.string(), "frame " + std::to_string(frame) + " (" + std::to_string(w) + "x" +
                                                 std::to_string(h) + " LR) is smaller than a crop of " +
                                                 std::to_string(side) + " pixels with its margin");
    const torch::Tensor net_info = network_->info_input(b);
    for (int k = 0; k < crops.crops_per_frame; ++k) {
      std::uniform_int_distribution<int64_t> py(0, h - side), px(0, w - side);
      const int64_t y = py(rng), x = px(rng);
      lr.push_back(b.lr_color.narrow(2, y, side).narrow(3, x, side));
      hr.push_back(b.hr_color.narrow(2, y * scale, side * scale).narrow(3, x * scale, side * scale));
      if (net_info.defined()) {
        const int64_t f = network_->spec().rit.reads_hr() ? scale : 1;
        info.push_back(net_info.narrow(2, y * f, side * f).narrow(3, x * f, side * f));
      }
      if (edges) {
        const auto e = pick_channels(b.hr_info, b.channels, {RenderChannel::Edge}, "hr_info", "the evaluator");
        mask.push_back(dilate_edges(e[0]).narrow(1, y * scale, side * scale).narrow(2, x * scale, side * scale)
                           .unsqueeze(0));
      }
    }
  }
  lr_color_ = torch::cat(lr).contiguous();
  hr_color_ = torch::cat(hr).contiguous();
  if (!info.empty()) info_ = torch::cat(info).contiguous();
  if (!mask.empty()) edge_mask_ = torch::cat(mask).contiguous();
  margin_hr_ = crops.margin * scale;
}

SubnetScore InferenceEvaluator::evaluate(const SubnetConfig& subnet) {
  torch::NoGradGuard no_grad;
  const graph::Graph g = subnet_graph(*network_, subnet);
  const auto cut = [&](const torch::Tensor& t) {
    const int64_t n = t.size(2) - 2 * margin_hr_;
    return t.narrow(2, margin_hr_, n).narrow(3, margin_hr_, n);
  };
  const torch::Tensor sr = cut(graph::run(g, network_inputs(g, lr_color_, info_)).front().second.clamp(0, 1));
  const torch::Tensor err = (sr - cut(hr_color_)).square();
  const double mse = err.mean().item<double>();
  if (!std::isfinite(mse)) throw Error("subnet " + subnet_key(subnet), "its output is not finite");
  const auto to_psnr = [](double m) { return m > 0 ? -10.0 * std::log10(m) : INFINITY; };
  SubnetScore s;
  s.psnr = to_psnr(mse);
  if (edge_mask_.defined()) {
    const auto inside = cut(edge_mask_).expand_as(err);
    const double count = inside.sum().item<double>();
    if (count > 0) s.psnr_edge = to_psnr(err.masked_select(inside).sum().item<double>() / count);
  }
  s.latency_ms = table_.predict(g);
  const Complexity c = complexity(g, table_.lr_width, table_.lr_height);
  s.params = c.params;
  s.macs = c.macs;
  return s;
}

}  // namespace cgsr
