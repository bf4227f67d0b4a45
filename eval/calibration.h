#pragma once
// INT8 calibration of a trained network on rendered frames (models/precision.h): which frames,
// how many, and by which method, as configs and `cgsr eval` spell it.

#include <memory>
#include <string>

#include "core/config.h"
#include "eval/upscaler.h"
#include "models/precision.h"
#include "models/sr_network.h"
#include "render_data/dataset.h"

namespace cgsr {

struct CalibrationOptions {
  std::string split = "train";  // frames the evaluation does not score
  int frames = 16;              // spread evenly over the split
  // The percentile lost a third to a half of max's 0.03-0.07 dB on the quickstart's networks
  // (docs/results/precision.md).
  CalibrationMethod method = CalibrationMethod::Percentile;
};
config::Schema<CalibrationOptions> calibration_schema_fields();

// What a network reads on the calibration frames `options` pick of `data`: per frame, its graph
// inputs (network_inputs of `graph`, a graph of `net` or of a subnet of it). Error naming the
// data set when the split has no frames.
std::vector<std::vector<std::pair<std::string, torch::Tensor>>> calibration_inputs(const SRNetworkImpl& net,
                                                                                   const graph::Graph& graph,
                                                                                   const Dataset& data,
                                                                                   const CalibrationOptions& options);

// The ranges of `net`'s activations on whole frames of `data` (LR colour and the rendering
// information the network reads).
Calibration calibrate_network(SRNetworkImpl& net, const Dataset& data, const CalibrationOptions& options);

// A network's row name in a precision: "<network> int8" (fp32 keeps the network's name); and back.
std::string precision_row_name(const std::string& network, Precision precision);
std::string network_of_row(const std::string& row, Precision precision);

// `network` on the fused path in `precision`, named by precision_row_name; INT8 calibrated on
// `data` as `options` say.
std::unique_ptr<NetworkUpscaler> network_in_precision(const NetworkUpscaler& network, Precision precision,
                                                      const Dataset& data, const CalibrationOptions& options);

}  // namespace cgsr
