#include "search/subnet_evaluator.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/runtime.h"
#include "models/complexity.h"
#include "models/fused_graph.h"
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

namespace {

// `per_frame` crops of `side` LR pixels at random positions of each frame, with the HR colour and
// edge mask when asked.
InferenceEvaluator::Crops draw_crops(const SRNetworkImpl& net, const Dataset& data, const std::vector<int>& frames,
                                     int per_frame, int side, const std::vector<RenderChannel>& channels,
                                     bool with_hr, bool edges, std::mt19937_64& rng) {
  const int scale = net.spec().scale;
  std::vector<torch::Tensor> lr, info, hr, mask;
  for (int frame : frames) {
    const Batch b = frame_batch(data, frame, scale, channels, net.depth_encoding());
    const int64_t h = b.lr_color.size(2), w = b.lr_color.size(3);
    if (h < side || w < side)
      throw Error(data.info().root.string(), "frame " + std::to_string(frame) + " (" + std::to_string(w) + "x" +
                                                 std::to_string(h) + " LR) is smaller than a crop of " +
                                                 std::to_string(side) + " pixels with its margin");
    const torch::Tensor net_info = net.info_input(b);
    for (int k = 0; k < per_frame; ++k) {
      std::uniform_int_distribution<int64_t> py(0, h - side), px(0, w - side);
      const int64_t y = py(rng), x = px(rng);
      lr.push_back(b.lr_color.narrow(2, y, side).narrow(3, x, side));
      if (with_hr) hr.push_back(b.hr_color.narrow(2, y * scale, side * scale).narrow(3, x * scale, side * scale));
      if (net_info.defined()) {
        const int64_t f = net.spec().rit.reads_hr() ? scale : 1;
        info.push_back(net_info.narrow(2, y * f, side * f).narrow(3, x * f, side * f));
      }
      if (with_hr && edges) {
        const auto e = pick_channels(b.hr_info, b.channels, {RenderChannel::Edge}, "hr_info", "the evaluator");
        mask.push_back(dilate_edges(e[0]).narrow(1, y * scale, side * scale).narrow(2, x * scale, side * scale)
                           .unsqueeze(0));
      }
    }
  }
  InferenceEvaluator::Crops c;
  c.lr_color = torch::cat(lr).contiguous();
  if (!hr.empty()) c.hr_color = torch::cat(hr).contiguous();
  if (!info.empty()) c.info = torch::cat(info).contiguous();
  if (!mask.empty()) c.edge_mask = torch::cat(mask).contiguous();
  return c;
}

}  // namespace

InferenceEvaluator::InferenceEvaluator(SRNetwork network, const Dataset& data, const ValidationCropOptions& crops,
                                       std::map<Precision, LatencyTable> tables)
    : network_(std::move(network)), tables_(std::move(tables)) {
  if (!tables_.count(Precision::Fp32)) throw Error("subnet evaluator", "no float32 latency table");
  network_->eval();
  std::vector<int> frames = spread_frames(data.frames(Split::Val), crops.frames);
  if (frames.empty()) frames = spread_frames(data.frames(Split::Train), std::max(1, crops.frames));
  if (frames.empty()) throw Error(data.info().root.string(), "no frames to score subnets on");
  const auto [lr_res, hr_res] = resolution_pair(data, network_->spec().scale);
  const auto& hr_channels = channels_at(data.info(), hr_res);
  const bool edges = std::find(hr_channels.begin(), hr_channels.end(), RenderChannel::Edge) != hr_channels.end();
  std::vector<RenderChannel> channels = network_->input_channels();
  if (edges && std::find(channels.begin(), channels.end(), RenderChannel::Edge) == channels.end())
    channels.push_back(RenderChannel::Edge);

  auto rng = make_rng("subnet-evaluator-crops");
  const int side = crops.size + 2 * crops.margin;
  scored_ = draw_crops(*network_, data, frames, crops.crops_per_frame, side, channels, true, edges, rng);
  margin_hr_ = crops.margin * network_->spec().scale;
  if (tables_.count(Precision::Int8)) {
    std::vector<int> train = spread_frames(data.frames(Split::Train), crops.frames);
    if (train.empty()) train = frames;
    auto calibration_rng = make_rng("subnet-evaluator-calibration");
    calibration_ = draw_crops(*network_, data, train, crops.crops_per_frame, side, network_->input_channels(),
                                     false, false, calibration_rng);
  }
}

SubnetScore InferenceEvaluator::evaluate(const SubnetConfig& subnet) {
  torch::NoGradGuard no_grad;
  const auto table = tables_.find(subnet.precision);
  if (table == tables_.end())
    throw Error("subnet " + subnet_key(subnet), "no " + enum_name(subnet.precision) + " latency table");
  const graph::Graph g = subnet_graph(*network_, subnet);
  const auto cut = [&](const torch::Tensor& t) {
    const int64_t n = t.size(2) - 2 * margin_hr_;
    return t.narrow(2, margin_hr_, n).narrow(3, margin_hr_, n);
  };
  const auto inputs = network_inputs(g, scored_.lr_color, scored_.info);
  FusedGraph::Options o;
  o.precision = subnet.precision;
  if (subnet.precision == Precision::Int8)
    o.calibration = calibrate(g, {network_inputs(g, calibration_.lr_color, calibration_.info)},
                              CalibrationMethod::Percentile);
  const torch::Tensor out = FusedGraph(g, o).run(inputs).front().second;
  const torch::Tensor sr = cut(out.clamp(0, 1));
  const torch::Tensor err = (sr - cut(scored_.hr_color)).square();
  const double mse = err.mean().item<double>();
  if (!std::isfinite(mse)) throw Error("subnet " + subnet_key(subnet), "its output is not finite");
  const auto to_psnr = [](double m) { return m > 0 ? -10.0 * std::log10(m) : INFINITY; };
  SubnetScore s;
  s.psnr = to_psnr(mse);
  if (scored_.edge_mask.defined()) {
    const auto inside = cut(scored_.edge_mask).expand_as(err);
    const double count = inside.sum().item<double>();
    if (count > 0) s.psnr_edge = to_psnr(err.masked_select(inside).sum().item<double>() / count);
  }
  s.latency_ms = table->second.predict(g);
  const Complexity c = complexity(g, table->second.lr_width, table->second.lr_height);
  s.params = c.params;
  s.macs = c.macs;
  return s;
}

}  // namespace cgsr
