#pragma once
// Scores subnets of an elastic network by inference: PSNR (and PSNR on geometry-edge pixels) on a
// fixed set of validation crops, latency predicted by the network's latency table, parameters
// and MACs counted on the subnet's graph. No training: a subnet's weights are views of the
// elastic network's (models/subnet.h), so thousands are scored in the time one used to train.
//
// The crops are drawn once, at random positions of validation frames spread over the split, and
// shared by every subnet, so differences between subnets are not sampling noise. Each crop is run
// with a margin of LR pixels around it that is cut off before scoring, so the crop's borders
// (zero padding where the frame goes on) do not count.

#include <optional>
#include <vector>

#include "core/config.h"
#include "models/latency_table.h"
#include "models/sr_network.h"
#include "render_data/dataset.h"
#include "search/evaluator.h"

namespace cgsr {

struct ValidationCropOptions {
  int frames = 8;          // validation frames (spread over the split; 0: all)
  int crops_per_frame = 2;
  int size = 48;           // LR pixels scored per crop side
  int margin = 4;          // LR pixels run around the crop and cut off
};
config::Schema<ValidationCropOptions> validation_crop_schema();

class InferenceEvaluator : public Evaluator {
 public:
  // `data` must carry the network's rendering channels (and edges, for edge PSNR).
  InferenceEvaluator(SRNetwork network, const Dataset& data, const ValidationCropOptions& crops, LatencyTable table);

  SubnetScore evaluate(const SubnetConfig& subnet) override;
  const LatencyTable& latency_table() const { return table_; }
  int crops() const { return static_cast<int>(lr_color_.size(0)); }

 private:
  SRNetwork network_;
  LatencyTable table_;
  int margin_hr_ = 0;
  torch::Tensor lr_color_, info_, hr_color_, edge_mask_;  // crops stacked [N, ...]; mask [N,1,H,W] or undefined
};

}  // namespace cgsr
