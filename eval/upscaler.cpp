#include "eval/upscaler.h"

#include <torch/torch.h>

#include "core/error.h"
#include "eval/baselines/bsp_border_upsampler.h"
#include "eval/baselines/fsr1.h"
#include "eval/baselines/history_fill.h"
#include "eval/baselines/interpolation.h"
#include "models/inference.h"
#include "render_data/history_channel.h"

namespace cgsr {
namespace {
class ClassicUpscaler : public Upscaler {
 public:
  using Function = std::function<torch::Tensor(const torch::Tensor&, int)>;
  ClassicUpscaler(std::string name, int scale, Function f) : name_(std::move(name)), scale_(scale), f_(std::move(f)) {}
  std::string name() const override { return name_; }
  int scale() const override { return scale_; }
  torch::Tensor upscale(const Batch& batch) override {
    torch::NoGradGuard no_grad;
    return f_(batch.lr_color, scale_);
  }

 private:
  std::string name_;
  int scale_;
  Function f_;
};

// The BSP border upsampler: the batch's BSP border images besides its colour.
class BspBorderUpscaler : public Upscaler {
 public:
  explicit BspBorderUpscaler(int scale) : scale_(scale) {}
  std::string name() const override { return "bsp_border"; }
  int scale() const override { return scale_; }
  bool reads_bsp_border() const override { return true; }
  torch::Tensor upscale(const Batch& batch) override {
    torch::NoGradGuard no_grad;
    if (batch.lr_bsp_border.empty())
      throw Error("bsp_border", "the frames carry no sub-pixel BSP border images: evaluate it on a data set rendered "
                                "with bsp_border: {depth: 2} (docs/bsp_border.md)");
    std::vector<const BspBorderImage*> images;
    for (const auto& b : batch.lr_bsp_border) images.push_back(b.get());
    return upscale_bsp_border(batch.lr_color, images, scale_);
  }

 private:
  int scale_;
};

// Bicubic at the unjittered output grid, from each frame's jitter (Batch::lr_jitter; an engine
// knows its jitter); plain bicubic for batches without one.
class JitteredBicubicUpscaler : public Upscaler {
 public:
  explicit JitteredBicubicUpscaler(int scale) : scale_(scale) {}
  std::string name() const override { return "bicubic_at_jitter"; }
  int scale() const override { return scale_; }
  bool reads_jitter() const override { return true; }
  torch::Tensor upscale(const Batch& batch) override {
    torch::NoGradGuard no_grad;
    return batch.lr_jitter.empty() ? upscale_bicubic(batch.lr_color, scale_)
                                   : upscale_bicubic_jittered(batch.lr_color, scale_, batch.lr_jitter);
  }

 private:
  int scale_;
};

// The history-fill upscaler: the batch's `history` channel at the output resolution.
class HistoryFillUpscaler : public Upscaler {
 public:
  explicit HistoryFillUpscaler(int scale) : scale_(scale) {}
  std::string name() const override { return "history"; }
  int scale() const override { return scale_; }
  std::vector<RenderChannel> channels() const override { return {RenderChannel::History}; }
  bool reads_jitter() const override { return true; }
  torch::Tensor upscale(const Batch& batch) override {
    torch::NoGradGuard no_grad;
    if (!batch.hr_info.defined() || batch.hr_info.numel() == 0)
      throw Error("history", "the frames carry no history channel at the output resolution: evaluate it on a data set "
                             "with motion and depth at that resolution (docs/temporal.md)");
    const auto history = pick_channels(batch.hr_info, batch.channels, channels(), "hr_info", "the history upscaler");
    return upscale_history_fill(batch.lr_color, history, scale_, batch.lr_jitter);
  }

 private:
  int scale_;
};

void add_classic(Registry<ClassicFactory>& r, const std::string& name, ClassicUpscaler::Function f,
                 const std::string& description) {
  r.add(name, [name, f](int scale) { return std::make_unique<ClassicUpscaler>(name, scale, f); }, description);
}
}  // namespace

const Registry<ClassicFactory>& classic_upscalers() {
  static const Registry<ClassicFactory> registry = [] {
    Registry<ClassicFactory> r("classic upscaler");
    add_classic(r, "nearest", upscale_nearest, "nearest neighbour");
    add_classic(r, "bilinear", upscale_bilinear, "bilinear");
    add_classic(r, "bicubic", upscale_bicubic, "bicubic (Keys, a = -0.75)");
    add_classic(r, "lanczos", [](const torch::Tensor& x, int s) { return upscale_lanczos(x, s, 3); }, "Lanczos-3");
    add_classic(r, "fsr", [](const torch::Tensor& x, int s) { return upscale_fsr1(x, s); },
                "FSR 1.0-style EASU + RCAS");
    r.add("bsp_border", [](int scale) { return std::make_unique<BspBorderUpscaler>(scale); },
          "leaves of the renderer's sub-pixel BSP border images, bicubic elsewhere (data sets rendered with bsp_border)");
    r.add("bicubic_at_jitter", [](int scale) { return std::make_unique<JitteredBicubicUpscaler>(scale); },
          "bicubic at the unjittered output grid, from each frame's jitter (bicubic on unjittered frames)");
    r.add("history", [](int scale) { return std::make_unique<HistoryFillUpscaler>(scale); },
          "the reprojected samples of the history channel where it has one, bicubic elsewhere (data sets with motion)");
    return r;
  }();
  return registry;
}

NetworkUpscaler::NetworkUpscaler(std::string name, SRNetwork network, InferenceEngine engine,
                                 FusedGraph::Options fused)
    : name_(std::move(name)), network_(std::move(network)), engine_(engine), fused_options_(std::move(fused)) {
  CGSR_CHECK(engine_ == InferenceEngine::Fused || fused_options_.precision == Precision::Fp32,
             "network upscaler: only the fused engine runs in reduced precision");
}

bool NetworkUpscaler::recurrent() const { return reads_previous_output(network_->input_channels()); }

void NetworkUpscaler::reset_history() {
  previous_ = torch::Tensor();
  previous_frame_ = -1;
}

torch::Tensor NetworkUpscaler::upscale(const Batch& batch) {
  const int frame = batch.frames.size() == 1 ? batch.frames.front() : -1;
  const bool recurs = recurrent();
  const bool follows = recurs && previous_.defined() && frame >= 0 && frame == previous_frame_ + 1;
  const auto info = network_->info_input(batch, follows ? previous_ : torch::Tensor());
  torch::Tensor out;
  if (engine_ == InferenceEngine::LibTorch) {
    out = infer(*network_, batch.lr_color, info);
  } else {
    if (!fused_) {
      network_->eval();
      fused_ = std::make_shared<FusedGraph>(network_->describe(), fused_options_);
    }
    out = fused_->run(batch.lr_color, info);
  }
  if (recurs) {
    previous_ = out;
    previous_frame_ = frame;
  }
  return out;
}

std::optional<Complexity> NetworkUpscaler::cost(int64_t lr_width, int64_t lr_height) const {
  return complexity(*network_, lr_width, lr_height);
}

}  // namespace cgsr
