#pragma once
// INT8 calibration of a trained network on rendered frames (models/precision.h): which frames,
// how many, and by which method, as configs and `cgsr eval` spell it.

#include "core/config.h"
#include "models/precision.h"
#include "models/sr_network.h"
#include "render_data/dataset.h"

namespace cgsr {

struct CalibrationOptions {
  std::string split = "train";  // frames the evaluation does not score
  int frames = 16;              // spread evenly over the split
  CalibrationMethod method = CalibrationMethod::Max;
};
config::Schema<CalibrationOptions> calibration_schema_fields();

// The ranges of `net`'s activations on whole frames of `data` (LR colour and the rendering
// information the network reads). Error naming the data set when the split has no frames.
Calibration calibrate_network(SRNetworkImpl& net, const Dataset& data, const CalibrationOptions& options);

}  // namespace cgsr
