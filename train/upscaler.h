#pragma once
// Anything evaluation can run: a classic interpolator or FSR-style filter, or a network. Eval,
// report and the quickstart treat them alike, so every row of a report comes from one code path.

#include <torch/types.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/registry.h"
#include "models/complexity.h"
#include "models/sr_network.h"
#include "render_data/batch.h"

namespace cgsr {

class Upscaler {
 public:
  virtual ~Upscaler() = default;
  virtual std::string name() const = 0;
  virtual int scale() const = 0;
  // Rendering channels the upscaler reads from a Batch (at LR and/or HR as its spec says).
  virtual std::vector<RenderChannel> channels() const { return {}; }
  // [N, 3, s*h, s*w] in [0,1]-ish (not clamped), without autograd.
  virtual torch::Tensor upscale(const Batch& batch) = 0;
  // Parameters and MACs at an LR size; nullopt for classic filters (the paper's "NA").
  virtual std::optional<Complexity> cost(int64_t lr_width, int64_t lr_height) const { return std::nullopt; }
};

// nearest, bilinear, bicubic, lanczos, fsr
using ClassicFactory = std::function<std::unique_ptr<Upscaler>(int scale)>;
const Registry<ClassicFactory>& classic_upscalers();

class NetworkUpscaler : public Upscaler {
 public:
  NetworkUpscaler(std::string name, SRNetwork network);
  std::string name() const override { return name_; }
  int scale() const override { return network_->spec().scale; }
  std::vector<RenderChannel> channels() const override { return network_->input_channels(); }
  torch::Tensor upscale(const Batch& batch) override;
  std::optional<Complexity> cost(int64_t lr_width, int64_t lr_height) const override;
  SRNetwork network() const { return network_; }

 private:
  std::string name_;
  SRNetwork network_;
};

}  // namespace cgsr
