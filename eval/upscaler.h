#pragma once
// Anything evaluation can run: a classic interpolator or FSR-style filter, or a network. Eval,
// report and the quickstart treat them alike, so every row of a report comes from one code path.

#include <torch/types.h>

#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/registry.h"
#include "models/complexity.h"
#include "models/fused_graph.h"
#include "models/inference.h"
#include "models/sr_network.h"
#include "render_data/batch.h"

namespace cgsr {

// What an upscaler that chooses a pattern per frame (a hybrid-pruned model:
// pruning/hybrid_upscaler.h) chose for one frame. The evaluation records it per frame
// (FrameScore::choice), the report and the verdict read it (pattern_choice.h).
struct PatternChoice {
  int pattern = 0;              // in the model's pattern pool; 0 is the widest (the static network)
  double channel_fraction = 1;  // of the widest pattern's unit channels
  bool previous_frame = false;  // the choice saw the previous frame's rendering information
  double choose_ms = 0;         // time spent choosing
};

class Upscaler {
 public:
  virtual ~Upscaler() = default;
  virtual std::string name() const = 0;
  virtual int scale() const = 0;
  // Rendering channels the upscaler reads from a Batch (at LR and/or HR as its spec says).
  virtual std::vector<RenderChannel> channels() const { return {}; }
  // The encoding of the depth channel in those batches.
  virtual DepthEncoding depth_encoding() const { return DepthEncoding::Log; }
  // [N, 3, s*h, s*w] in [0,1]-ish (not clamped), without autograd.
  virtual torch::Tensor upscale(const Batch& batch) = 0;
  // Parameters and MACs at an LR size; nullopt for classic filters (the paper's "NA").
  virtual std::optional<Complexity> cost(int64_t lr_width, int64_t lr_height) const { return std::nullopt; }

  // Upscalers whose output depends on the previous frame (per-frame dynamic pruning reads its
  // rendering information) say so; callers then pass that frame, with this upscaler's
  // channels(), to previous_frame() before upscale() of the frame after it.
  virtual bool uses_previous_frame() const { return false; }
  virtual void previous_frame(const Batch& previous) {}
  // The next frame has no predecessor (a sequence's first frame, or a scene cut in a multi-scene
  // data set): forget every frame seen so far.
  virtual void reset_history() {}
  // Recurrent upscalers read their own output for the frame before (history_out): callers run
  // every frame of a scene in order, from its first (or the last one run), calling reset_history()
  // at its first. A frame that does not follow the last one run starts without that output.
  virtual bool recurrent() const { return false; }
  // The pattern the last upscale() chose, for the per-frame record; none for upscalers that
  // choose nothing.
  virtual std::optional<PatternChoice> frame_choice() const { return std::nullopt; }
  // The number format its network computes in (models/precision.h).
  virtual Precision precision() const { return Precision::Fp32; }
  // Reads the batches' sub-pixel BSP border images (Batch::lr_bsp_border): runs only on data
  // sets rendered with them (DatasetInfo::bsp_border).
  virtual bool reads_bsp_border() const { return false; }
  // Reads each frame's jitter (Batch::lr_jitter): meant for jittered data sets.
  virtual bool reads_jitter() const { return false; }
};

// nearest, bilinear, bicubic, lanczos, fsr, bsp_border (only on data sets with BSP border files),
// and for jittered frames bicubic_at_jitter and history (eval/baselines/history_fill.h)
using ClassicFactory = std::function<std::unique_ptr<Upscaler>(int scale)>;
const Registry<ClassicFactory>& classic_upscalers();

// A trained network, run by the fused inference path unless told otherwise (in the precision of
// `fused`, which for INT8 carries the calibration). The fused path snapshots the weights at the
// first upscale(): the network must not change after that.
class NetworkUpscaler : public Upscaler {
 public:
  NetworkUpscaler(std::string name, SRNetwork network, InferenceEngine engine = InferenceEngine::Fused,
                  FusedGraph::Options fused = {});
  std::string name() const override { return name_; }
  int scale() const override { return network_->spec().scale; }
  std::vector<RenderChannel> channels() const override { return network_->input_channels(); }
  DepthEncoding depth_encoding() const override { return network_->depth_encoding(); }
  torch::Tensor upscale(const Batch& batch) override;
  std::optional<Complexity> cost(int64_t lr_width, int64_t lr_height) const override;
  SRNetwork network() const { return network_; }
  Precision precision() const override { return fused_options_.precision; }
  bool recurrent() const override;
  void reset_history() override;

 private:
  std::string name_;
  SRNetwork network_;
  InferenceEngine engine_;
  FusedGraph::Options fused_options_;
  std::shared_ptr<FusedGraph> fused_;  // built at the first upscale()
  // A recurrent network's last output and its frame (-1: none).
  torch::Tensor previous_;
  int previous_frame_ = -1;
};

}  // namespace cgsr
