#include "eval/upscaler.h"

#include <torch/torch.h>

#include "core/error.h"
#include "eval/baselines/bsp_border_upsampler.h"
#include "eval/baselines/fsr1.h"
#include "eval/baselines/interpolation.h"
#include "models/inference.h"

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

torch::Tensor NetworkUpscaler::upscale(const Batch& batch) {
  const auto info = network_->info_input(batch);
  if (engine_ == InferenceEngine::LibTorch) return infer(*network_, batch.lr_color, info);
  if (!fused_) {
    network_->eval();
    fused_ = std::make_shared<FusedGraph>(network_->describe(), fused_options_);
  }
  return fused_->run(batch.lr_color, info);
}

std::optional<Complexity> NetworkUpscaler::cost(int64_t lr_width, int64_t lr_height) const {
  return complexity(*network_, lr_width, lr_height);
}

}  // namespace cgsr
