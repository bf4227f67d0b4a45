#pragma once
// Latency of subnets on this machine, predicted without running them (Once-for-All's latency
// lookup table), so a search can price thousands of candidates.
//
// Every convolution of a subnet's graph is looked up by its shape (kernel, input and output
// channels, stride, spatial factor), timed once on the fused path (fused_graph.h) at the table's
// LR size; the other ops (element-wise ops, resizes, pixel shuffles), most of which the fused
// path folds into convolutions, are charged per output element. A linear calibration against
// whole subnets measured on the fused path, latency = a * sum(conv) + b * elements + c with no
// coefficient negative, absorbs what the sum misses: fusions, memory traffic between layers, the
// fixed cost of a run. Its error on subnets it was not fitted on is recorded with the table.
//
// A table is measured for one precision (precision.h). In bf16 or int8 the convolutions that
// compute in it are timed so, and their keys end in the format ("..._f1_int8"); the wide ones
// (low_precision_convs) keep float32 keys and times. A lone convolution is timed as an inner one
// would run (FusedGraph::Options::low_convs), reading a float32 input it converts; the
// calibration absorbs the difference.
//
//   LatencyTable table = measure_latency_table(*net, space, 320, 240, options, Precision::Int8);
//   double ms = table.predict(subnet_graph(*net, sub));

#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/config.h"
#include "models/elastic.h"
#include "models/graph.h"
#include "models/precision.h"
#include "models/sr_network.h"

namespace cgsr {

struct LatencyTableOptions {
  int runs = 5;              // timed runs per convolution shape (median), after 2 warm-up runs
  int calibration_subnets = 6;  // whole subnets measured to fit the calibration (plus full and smallest)
  int check_subnets = 6;        // whole subnets measured to report the prediction error
  int subnet_runs = 3;          // timed runs per whole subnet (median)
  uint64_t seed = 0;            // draws the subnets
};
config::Schema<LatencyTableOptions> latency_table_schema();

// How well predictions matched measured latency on subnets the calibration was not fitted on.
struct PredictionError {
  int subnets = 0;
  double mean_abs_percent = 0, max_abs_percent = 0;
  std::vector<double> predicted_ms, measured_ms;
};

struct LatencyTable {
  Precision precision = Precision::Fp32;
  int64_t lr_width = 0, lr_height = 0;
  int threads = 0;
  std::map<std::string, double> conv_ms;  // shape key -> median ms
  double scale = 1, element_ns = 0, offset_ms = 0;  // calibration
  PredictionError error;

  // The features the calibration weighs: the table's convolutions summed (ms) and the other
  // ops' output elements at the table's size. Error naming the op when a shape is not in the table.
  std::pair<double, double> features(const graph::Graph& graph) const;
  double predict(const graph::Graph& graph) const;
  double predict(double conv_ms, double elements) const;  // from the features
};

// One whole subnet's calibration point: its features and its measured latency.
struct LatencySample {
  double conv_ms = 0, elements = 0, measured_ms = 0;
};

// Sets the table's calibration to the least-squares fit of the samples with every coefficient
// non-negative (the scale positive), so predictions never fall below zero or as a subnet grows.
void fit_calibration(LatencyTable& table, const std::vector<LatencySample>& samples);

// "k3_i20_o40_s1_p1_g1_f1": a convolution's shape key (without a precision).
std::string conv_shape_key(const graph::Graph& graph, const graph::Op& op);

// Times every convolution shape the space's subnets can have, then calibrates on whole subnets,
// all in `precision`.
LatencyTable measure_latency_table(const SRNetworkImpl& net, const ElasticSpace& space, int64_t lr_width,
                                   int64_t lr_height, const LatencyTableOptions& options,
                                   Precision precision = Precision::Fp32);

// Measured fused-path latency (median ms) of a graph at an LR size in `precision`: one random
// input of the graph's shape (int8 calibrated on it), `runs` timed runs after two warm-up runs.
double measure_graph_latency(const graph::Graph& graph, int64_t lr_width, int64_t lr_height, int runs,
                             Precision precision = Precision::Fp32);

nlohmann::ordered_json to_json(const LatencyTable& table);
LatencyTable latency_table_from_json(const nlohmann::ordered_json& j, const std::string& context);

// Where a model file's provenance keeps the table of a precision: "latency_table" (float32),
// "latency_table_int8", "latency_table_bf16".
std::string latency_table_key(Precision precision);
// Every table in a provenance's `extra`, by precision (empty when it has none).
std::map<Precision, LatencyTable> latency_tables_from(const nlohmann::ordered_json& extra, const std::string& context);

}  // namespace cgsr
