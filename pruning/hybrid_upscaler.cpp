#include "pruning/hybrid_upscaler.h"

#include <spdlog/spdlog.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace cgsr {

HybridUpscaler::HybridUpscaler(std::string name, HybridModel model, Precision precision,
                               const PatternCalibration& calibration)
    : name_(std::move(name)), model_(std::move(model)) {
  model_.network->eval();
  model_.samplers->eval();
  sampler_channels_ = model_.samplers->options().render_channels();
  channels_ = model_.network->input_channels();
  for (auto c : sampler_channels_)
    if (std::find(channels_.begin(), channels_.end(), c) == channels_.end()) channels_.push_back(c);
  std::sort(channels_.begin(), channels_.end());
  patterns_ = std::make_unique<PatternNetworks>(*model_.network, model_.pool, precision, calibration);
  usage_.assign(model_.pool.size(), 0);
}

torch::Tensor HybridUpscaler::sampler_info(const Batch& batch) const {
  return pick_channels(batch.lr_info, batch.channels, sampler_channels_, "lr_info", "the dynamic samplers");
}

void HybridUpscaler::previous_frame(const Batch& previous) {
  previous_info_ = sampler_info(previous);
  previous_frame_ = previous.frames.empty() ? -1 : previous.frames.front();
}

void HybridUpscaler::reset_history() {
  previous_info_ = last_info_ = torch::Tensor();
  previous_frame_ = last_frame_ = -1;
}

int HybridUpscaler::choose(const Batch& batch) {
  if (batch.lr_color.size(0) != 1)
    throw Error("hybrid-pruned model", "chooses patterns per frame: give one frame at a time, got a batch of " +
                                           std::to_string(batch.lr_color.size(0)));
  torch::NoGradGuard no_grad;
  const auto info = sampler_info(batch);
  const int frame = batch.frames.empty() ? -1 : batch.frames.front();
  torch::Tensor previous;
  bool has_previous = false;
  if (previous_info_.defined() && frame >= 0 && previous_frame_ == frame - 1) {
    previous = previous_info_;
    has_previous = true;
  } else if (last_info_.defined() && frame >= 0 && last_frame_ == frame - 1) {
    previous = last_info_;
    has_previous = true;
  }
  if (previous.defined() && previous.sizes() != info.sizes()) {
    previous = torch::Tensor();
    has_previous = false;
  }
  const auto input = sampler_input(info, previous, sampler_channels_, model_.samplers->options().grid);
  const int choice = model_.samplers->choose(input).front().front();
  previous_info_ = torch::Tensor();
  previous_frame_ = -1;
  last_info_ = info;
  last_frame_ = frame;
  chose_with_previous_ = has_previous;
  return choice;
}

torch::Tensor HybridUpscaler::upscale(const Batch& batch) {
  const auto start = std::chrono::steady_clock::now();
  const int k = choose(batch);
  const double choose_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  const auto out = patterns_->run(k, batch.lr_color, model_.network->info_input(batch));
  ++usage_[k];
  choice_ = PatternChoice{k, model_.pool.channel_fraction(k), chose_with_previous_, choose_ms};
  return out;
}

std::optional<Complexity> HybridUpscaler::cost(int64_t lr_width, int64_t lr_height) const {
  int64_t frames = 0;
  for (int64_t n : usage_) frames += n;
  Complexity c = patterns_->cost(0, lr_width, lr_height);
  if (frames > 0) {
    double macs = 0;
    for (int k = 0; k < model_.pool.size(); ++k)
      if (usage_[k] > 0) macs += static_cast<double>(usage_[k]) * static_cast<double>(patterns_->cost(k, lr_width, lr_height).macs);
    c.macs = static_cast<int64_t>(std::llround(macs / static_cast<double>(frames)));
  }
  LayerCost sampler;
  sampler.name = "dynamic_sampler";
  sampler.kind = "dynamic_sampler";
  sampler.params = model_.samplers->parameter_count();
  sampler.macs = model_.samplers->macs();
  c.layers.push_back(sampler);
  c.params += sampler.params;
  c.macs += sampler.macs;
  return c;
}

std::unique_ptr<HybridUpscaler> hybrid_in_precision(const HybridUpscaler& hybrid, Precision precision,
                                                    const Dataset& data, const CalibrationOptions& options) {
  PatternCalibration calibration;
  calibration.method = options.method;
  if (precision == Precision::Int8) {
    const SRNetworkImpl& net = *hybrid.model().network;
    calibration.frames = calibration_inputs(net, net.describe(), data, options);
    spdlog::info("calibrating int8 activations of {}'s {} patterns on {} {} frame(s) ({})", hybrid.name(),
                 hybrid.model().pool.size(), calibration.frames.size(), options.split, enum_name(options.method));
  }
  return std::make_unique<HybridUpscaler>(precision_row_name(hybrid.name(), precision), hybrid.model(), precision,
                                          calibration);
}

std::unique_ptr<Upscaler> make_hybrid_upscaler(const std::filesystem::path& path, const std::string& name) {
  HybridModel model = load_hybrid_model(path);
  std::string display = name;
  if (display.empty()) display = model.provenance.extra.value("name", path.stem().string());
  return std::make_unique<HybridUpscaler>(display, std::move(model));
}

}  // namespace cgsr
