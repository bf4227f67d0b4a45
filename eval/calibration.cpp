#include "eval/calibration.h"

#include <spdlog/spdlog.h>

#include "render_data/patch_sampler.h"

namespace cgsr {

config::Schema<CalibrationOptions> calibration_schema_fields() {
  config::Schema<CalibrationOptions> s;
  s.field("split", &CalibrationOptions::split, "split the frames come from").one_of({"train", "val", "test", "all"});
  s.field("frames", &CalibrationOptions::frames, "frames measured, spread evenly over the split").range(1, 1000);
  s.field("method", &CalibrationOptions::method, "range of each activation: percentile (99.99th of |x|) or max");
  return s;
}

std::vector<std::vector<std::pair<std::string, torch::Tensor>>> calibration_inputs(const SRNetworkImpl& net,
                                                                                   const graph::Graph& graph,
                                                                                   const Dataset& data,
                                                                                   const CalibrationOptions& options) {
  const std::vector<int> frames = spread_frames(data.frames(split_from_name(options.split)), options.frames);
  if (frames.empty())
    throw Error(data.info().root.string(), "no " + options.split + " frames to calibrate int8 activations on");
  std::vector<std::vector<std::pair<std::string, torch::Tensor>>> inputs;
  for (int frame : frames) {
    const Batch b = frame_batch(data, frame, net.spec().scale, net.input_channels(), net.depth_encoding());
    inputs.push_back(network_inputs(graph, b.lr_color, net.info_input(b)));
  }
  return inputs;
}

Calibration calibrate_network(SRNetworkImpl& net, const Dataset& data, const CalibrationOptions& options) {
  net.eval();
  const graph::Graph g = net.describe();
  const auto inputs = calibration_inputs(net, g, data, options);
  spdlog::info("calibrating int8 activations of {} on {} {} frame(s) ({})", spec_summary(net.spec()), inputs.size(),
               options.split, enum_name(options.method));
  return calibrate(g, inputs, options.method);
}

std::string precision_row_name(const std::string& network, Precision precision) {
  return precision == Precision::Fp32 ? network : network + " " + enum_name(precision);
}

std::string network_of_row(const std::string& row, Precision precision) {
  const std::string suffix = precision_row_name("", precision);
  if (row.size() < suffix.size() || row.compare(row.size() - suffix.size(), suffix.size(), suffix) != 0)
    throw Error("report", "row '" + row + "' is not named as a network in " + enum_name(precision));
  return row.substr(0, row.size() - suffix.size());
}

std::unique_ptr<NetworkUpscaler> network_in_precision(const NetworkUpscaler& network, Precision precision,
                                                      const Dataset& data, const CalibrationOptions& options) {
  FusedGraph::Options fused;
  fused.precision = precision;
  if (precision == Precision::Int8) fused.calibration = calibrate_network(*network.network(), data, options);
  return std::make_unique<NetworkUpscaler>(precision_row_name(network.name(), precision), network.network(),
                                           InferenceEngine::Fused, fused);
}

}  // namespace cgsr
