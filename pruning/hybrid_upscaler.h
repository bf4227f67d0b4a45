#pragma once
// A hybrid-pruned model as an Upscaler: per frame, the dynamic pruning component scores the
// pool's patterns from the current and previous frame's rendering information, and the chosen
// pattern runs as its own narrow network on cgsr's fast path (pattern_networks.h). `cgsr eval`
// runs it through the same evaluation as every other upscaler; frame_choice() records the
// choice and the time spent choosing.
//
// The previous frame is the one given to previous_frame(), else the frame of the last
// upscale() call when it is the frame just before (a renderer calling it frame after frame),
// else none (its change is taken as zero). reset_history() forgets both: a scene cut, where the
// frame index goes on but the content does not.
//
// The patterns run in float32 unless a precision is given (pattern_networks.h); the choice
// always runs in float32 (a few thousand MACs).

#include <chrono>
#include <memory>

#include "eval/calibration.h"
#include "eval/upscaler.h"
#include "pruning/hybrid_model.h"
#include "pruning/pattern_networks.h"

namespace cgsr {

class HybridUpscaler : public Upscaler {
 public:
  HybridUpscaler(std::string name, HybridModel model, Precision precision = Precision::Fp32,
                 const PatternCalibration& calibration = {});

  std::string name() const override { return name_; }
  int scale() const override { return model_.network->spec().scale; }
  std::vector<RenderChannel> channels() const override { return channels_; }
  DepthEncoding depth_encoding() const override { return model_.network->depth_encoding(); }
  Precision precision() const override { return patterns_->precision(); }
  torch::Tensor upscale(const Batch& batch) override;
  // MACs: the mean over the frames upscaled so far (the widest pattern's before any); params:
  // what the model holds (the static network and the sampler).
  std::optional<Complexity> cost(int64_t lr_width, int64_t lr_height) const override;
  bool uses_previous_frame() const override { return true; }
  void previous_frame(const Batch& previous) override;
  void reset_history() override;
  std::optional<PatternChoice> frame_choice() const override { return choice_; }

  // The pattern chosen for a frame from its rendering information.
  int choose(const Batch& batch);
  const HybridModel& model() const { return model_; }
  // Frames per pattern among those upscaled so far.
  const std::vector<int64_t>& usage() const { return usage_; }

 private:
  torch::Tensor sampler_info(const Batch& batch) const;

  std::string name_;
  HybridModel model_;
  std::vector<RenderChannel> sampler_channels_, channels_;
  std::unique_ptr<PatternNetworks> patterns_;
  std::vector<int64_t> usage_;
  torch::Tensor previous_info_;   // sampler channels of the previous frame
  int previous_frame_ = -1;       // its frame index (-1: none)
  int last_frame_ = -1;           // frame of the last upscale()
  torch::Tensor last_info_;
  bool chose_with_previous_ = false;     // the last choose() saw a previous frame
  std::optional<PatternChoice> choice_;  // of the last upscale()
};

// `hybrid` with every pattern in `precision`, named by precision_row_name ("... int8"); INT8
// calibrates each pattern on `data` as `options` say.
std::unique_ptr<HybridUpscaler> hybrid_in_precision(const HybridUpscaler& hybrid, Precision precision,
                                                    const Dataset& data, const CalibrationOptions& options);

// Loads a hybrid-pruned model file as an upscaler; the display name defaults to the one recorded
// in the file (provenance.extra.name) or the file's stem.
std::unique_ptr<Upscaler> make_hybrid_upscaler(const std::filesystem::path& path, const std::string& name = "");

}  // namespace cgsr
