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
//
// A subnet runs on the fused path (models/fused_graph.h) in its precision (SubnetConfig::precision;
// float32 there is 1.8x faster than the interpreter on the quickstart's crops), int8 calibrated
// (99.99th percentile, models/precision.h) per subnet on as many crops drawn from training frames.
// Its latency comes from that precision's table.

#include <map>
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
  // `data` must carry the network's rendering channels (and edges, for edge PSNR). `tables`: a
  // latency table per precision the subnets may run in (float32 at least).
  InferenceEvaluator(SRNetwork network, const Dataset& data, const ValidationCropOptions& crops,
                     std::map<Precision, LatencyTable> tables);

  // Error naming the subnet when its precision has no latency table.
  SubnetScore evaluate(const SubnetConfig& subnet) override;
  const std::map<Precision, LatencyTable>& latency_tables() const { return tables_; }
  int crops() const { return static_cast<int>(scored_.lr_color.size(0)); }

  // Crops stacked [N, ...]; info, hr_color and edge_mask ([N,1,H,W]) undefined when not used.
  struct Crops {
    torch::Tensor lr_color, info, hr_color, edge_mask;
  };

 private:
  SRNetwork network_;
  std::map<Precision, LatencyTable> tables_;
  int margin_hr_ = 0;
  Crops scored_;       // from validation frames
  Crops calibration_;  // from training frames, when a table is int8
};

}  // namespace cgsr
