#include "models/latency_table.h"

#include <torch/torch.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <set>
#include <tuple>

#include "core/error.h"
#include "core/progress.h"
#include "core/timing.h"
#include "models/fused_graph.h"
#include "models/subnet.h"

namespace cgsr {

config::Schema<LatencyTableOptions> latency_table_schema() {
  config::Schema<LatencyTableOptions> s;
  s.field("runs", &LatencyTableOptions::runs, "timed runs per convolution shape (median)").range(1, 1000);
  s.field("calibration_subnets", &LatencyTableOptions::calibration_subnets,
          "random subnets measured whole to calibrate the sum").range(1, 1000);
  s.field("check_subnets", &LatencyTableOptions::check_subnets,
          "random subnets measured whole to report the prediction error").range(0, 1000);
  s.field("subnet_runs", &LatencyTableOptions::subnet_runs, "timed runs per whole subnet (median)").range(1, 1000);
  return s;
}

namespace {

struct ConvShape {
  int64_t kernel = 1, in = 0, out = 0, stride = 1, padding = 0, groups = 1, factor = 1;
  std::string key() const {
    return "k" + std::to_string(kernel) + "_i" + std::to_string(in) + "_o" + std::to_string(out) + "_s" +
           std::to_string(stride) + "_p" + std::to_string(padding) + "_g" + std::to_string(groups) + "_f" +
           std::to_string(factor);
  }
};

ConvShape shape_of(const graph::Graph& graph, const graph::Op& op) {
  return {op.kernel_size(),
          graph::layout_width(graph.values[op.inputs[0]].layout),
          graph::layout_width(graph.values[op.output].layout),
          op.stride,
          op.padding,
          op.groups,
          graph.values[op.output].factor};
}

// Widths a layout can take in the space's subnets: every combination of its groups' choices.
std::vector<int64_t> widths_of(const graph::Layout& layout, const std::map<std::string, std::vector<int64_t>>& choices,
                               const std::map<std::string, int64_t>& fixed) {
  std::set<int64_t> sums = {0};
  std::set<std::string> seen;
  for (const auto& s : layout) {
    std::vector<int64_t> options = {s.channels};
    if (s.prunable) {
      const auto it = choices.find(s.group);
      if (it != choices.end()) options = it->second;
      if (fixed.count(s.group)) options = {fixed.at(s.group)};
    }
    std::set<int64_t> next;
    for (int64_t sum : sums)
      for (int64_t w : options) next.insert(sum + w * s.repeat);
    sums = std::move(next);
  }
  return {sums.begin(), sums.end()};
}

// A fused graph of `graph` in `precision` for timing: int8 calibrated on `inputs` (the ranges
// change the values, not the time). `low_convs` as FusedGraph::Options has it.
FusedGraph timing_graph(const graph::Graph& graph, const std::vector<std::pair<std::string, torch::Tensor>>& inputs,
                        Precision precision, std::vector<bool> low_convs = {}) {
  FusedGraph::Options o;
  o.precision = precision;
  o.low_convs = std::move(low_convs);
  if (precision == Precision::Int8) o.calibration = calibrate(graph, {inputs}, CalibrationMethod::Max);
  return FusedGraph(graph, o);
}

// A lone convolution of the shape, in `precision` when `low`.
double time_conv(const ConvShape& c, int64_t w, int64_t h, int runs, Precision precision, bool low) {
  if (c.groups != 1) throw Error("latency table", "grouped convolutions are not timed", ErrorKind::Internal);
  graph::Builder b;
  const int x = b.input("x", graph::fixed_layout("x", c.in), c.factor * c.stride);
  const auto weight = torch::randn({c.out, c.in / c.groups, c.kernel, c.kernel}) * 0.1;
  const auto bias = torch::zeros({c.out});
  b.output("y", b.conv("conv", x, weight, bias, c.padding, graph::fixed_layout("y", c.out), true, c.stride));
  const graph::Graph g = b.finish();
  const std::vector<std::pair<std::string, torch::Tensor>> inputs = {
      {"x", torch::rand({1, c.in, h * c.factor * c.stride, w * c.factor * c.stride})}};
  FusedGraph fused = timing_graph(g, inputs, low ? precision : Precision::Fp32, std::vector<bool>(g.ops.size(), low));
  return measure_latency([&] { fused.run(inputs); }, /*warmup=*/2, runs).median_ms;
}

// Which convolutions of `graph` compute in `precision` (none in float32).
std::vector<bool> low_convs_in(const graph::Graph& graph, Precision precision) {
  return precision == Precision::Fp32 ? std::vector<bool>(graph.ops.size(), false) : low_precision_convs(graph);
}

std::string precision_key(const std::string& shape_key, Precision precision, bool low) {
  return low ? shape_key + "_" + enum_name(precision) : shape_key;
}

// The least-squares fit of y on the columns of x that `active` marks (the others' coefficients
// 0); false when degenerate.
bool fit_linear(const std::vector<LatencySample>& samples, const std::array<bool, 3>& active,
                std::array<double, 3>& out) {
  const auto column = [](const LatencySample& s, int c) { return c == 0 ? s.conv_ms : c == 1 ? s.elements * 1e-6 : 1.0; };
  std::vector<int> cols;
  for (int c = 0; c < 3; ++c)
    if (active[c]) cols.push_back(c);
  const int n = static_cast<int>(cols.size());
  double m[3][4] = {};
  for (const auto& s : samples)
    for (int r = 0; r < n; ++r) {
      for (int c = 0; c < n; ++c) m[r][c] += column(s, cols[r]) * column(s, cols[c]);
      m[r][3] += column(s, cols[r]) * s.measured_ms;
    }
  for (int col = 0; col < n; ++col) {
    int pivot = col;
    for (int r = col + 1; r < n; ++r)
      if (std::abs(m[r][col]) > std::abs(m[pivot][col])) pivot = r;
    if (std::abs(m[pivot][col]) < 1e-12) return false;
    for (int c = 0; c < 4; ++c) std::swap(m[col][c], m[pivot][c]);
    for (int r = 0; r < n; ++r) {
      if (r == col) continue;
      const double f = m[r][col] / m[col][col];
      for (int c = 0; c < 4; ++c) m[r][c] -= f * m[col][c];
    }
  }
  out = {0, 0, 0};
  for (int r = 0; r < n; ++r) out[cols[r]] = m[r][3] / m[r][r];
  return std::all_of(out.begin(), out.end(), [](double v) { return std::isfinite(v); });
}

}  // namespace

std::string conv_shape_key(const graph::Graph& graph, const graph::Op& op) { return shape_of(graph, op).key(); }

std::pair<double, double> LatencyTable::features(const graph::Graph& graph) const {
  double conv = 0, elements = 0;
  const std::vector<bool> low = low_convs_in(graph, precision);
  for (size_t i = 0; i < graph.ops.size(); ++i) {
    const auto& op = graph.ops[i];
    if (op.kind == graph::OpKind::Conv) {
      const std::string key = precision_key(conv_shape_key(graph, op), precision, low[i]);
      const auto it = conv_ms.find(key);
      if (it == conv_ms.end())
        throw Error("latency table", "no time for " + op.name + " (" + key + "); the subnet is outside the table's space");
      conv += it->second;
    } else {
      const auto& v = graph.values[op.output];
      elements += static_cast<double>(graph::layout_width(v.layout)) * (lr_width * v.factor) * (lr_height * v.factor);
    }
  }
  return {conv, elements};
}

void fit_calibration(LatencyTable& table, const std::vector<LatencySample>& samples) {
  // Non-negative least squares by trying every set of free coefficients (the conv sum's always
  // among them): an unconstrained fit to a few noisy timings can weigh elements negatively and
  // predict a small subnet slower than a large one, or below zero.
  double best_error = INFINITY;
  for (const std::array<bool, 3> active : {std::array<bool, 3>{true, true, true}, {true, true, false},
                                           {true, false, true}, {true, false, false}}) {
    std::array<double, 3> coef{};
    if (!fit_linear(samples, active, coef) || !(coef[0] > 0) || coef[1] < 0 || coef[2] < 0) continue;
    LatencyTable fitted;
    std::tie(fitted.scale, fitted.element_ns, fitted.offset_ms) = std::tie(coef[0], coef[1], coef[2]);
    double error = 0;
    for (const auto& s : samples) error += std::pow(fitted.predict(s.conv_ms, s.elements) - s.measured_ms, 2);
    if (error >= best_error) continue;
    best_error = error;
    std::tie(table.scale, table.element_ns, table.offset_ms) = std::tie(coef[0], coef[1], coef[2]);
  }
  if (std::isfinite(best_error)) return;
  // No timing or no convolution to fit: the sum as it is.
  table.scale = 1;
  table.element_ns = 0;
  table.offset_ms = 0;
}

double LatencyTable::predict(const graph::Graph& graph) const {
  const auto [conv, elements] = features(graph);
  return predict(conv, elements);
}

double LatencyTable::predict(double conv_ms, double elements) const {
  return scale * conv_ms + element_ns * 1e-6 * elements + offset_ms;
}

double measure_graph_latency(const graph::Graph& graph, int64_t lr_width, int64_t lr_height, int runs,
                             Precision precision) {
  std::vector<std::pair<std::string, torch::Tensor>> inputs;
  for (const auto& [name, v] : graph.inputs) {
    const auto& value = graph.values[v];
    inputs.emplace_back(name, torch::rand({1, graph::layout_width(value.layout), lr_height * value.factor,
                                           lr_width * value.factor}));
  }
  FusedGraph fused = timing_graph(graph, inputs, precision);
  return measure_latency([&] { fused.run(inputs); }, /*warmup=*/2, runs).median_ms;
}

LatencyTable measure_latency_table(const SRNetworkImpl& net, const ElasticSpace& space, int64_t lr_width,
                                   int64_t lr_height, const LatencyTableOptions& options, Precision precision) {
  torch::NoGradGuard no_grad;
  LatencyTable table;
  table.precision = precision;
  table.lr_width = lr_width;
  table.lr_height = lr_height;
  table.threads = torch::get_num_threads();
  const graph::Graph full = net.describe(false);
  std::map<std::string, std::vector<int64_t>> choices;
  for (const auto& gene : space.genes()) choices[gene.group] = gene.choices;
  // Subnets keep the full network's first and last layers, so its wide convolutions are theirs.
  const std::vector<bool> low = low_convs_in(full, precision);
  std::map<std::string, std::pair<ConvShape, bool>> shapes;  // key -> shape, computes low
  for (size_t i = 0; i < full.ops.size(); ++i) {
    const auto& op = full.ops[i];
    if (op.kind != graph::OpKind::Conv) continue;
    ConvShape base = shape_of(full, op);
    for (int64_t in : widths_of(full.values[op.inputs[0]].layout, choices, {}))
      for (int64_t out : widths_of(full.values[op.output].layout, choices, {})) {
        ConvShape c = base;
        c.in = in;
        c.out = out;
        shapes.emplace(precision_key(c.key(), precision, low[i]), std::make_pair(c, static_cast<bool>(low[i])));
      }
  }
  {
    Progress progress("latency table (" + enum_name(precision) + ")", static_cast<int64_t>(shapes.size()));
    for (const auto& [key, shape] : shapes) {
      table.conv_ms[key] = time_conv(shape.first, lr_width, lr_height, options.runs, precision, shape.second);
      progress.advance();
    }
  }
  // Whole subnets: the full network, the smallest and random ones to fit; others to check.
  std::mt19937_64 rng(options.seed);
  std::vector<SubnetConfig> fit_set = {space.full(), space.smallest()};
  for (int i = 0; i < options.calibration_subnets; ++i) fit_set.push_back(space.sample(rng));
  std::vector<SubnetConfig> check_set;
  for (int i = 0; i < options.check_subnets; ++i) check_set.push_back(space.sample(rng));
  Progress progress("latency calibration", static_cast<int64_t>(fit_set.size() + check_set.size()));
  std::vector<LatencySample> samples;
  for (const auto& sub : fit_set) {
    const graph::Graph g = subnet_graph(net, sub);
    const auto [conv, elements] = table.features(g);
    samples.push_back({conv, elements, measure_graph_latency(g, lr_width, lr_height, options.subnet_runs, precision)});
    progress.advance();
  }
  fit_calibration(table, samples);
  for (const auto& sub : check_set) {
    const graph::Graph g = subnet_graph(net, sub);
    table.error.predicted_ms.push_back(table.predict(g));
    table.error.measured_ms.push_back(measure_graph_latency(g, lr_width, lr_height, options.subnet_runs, precision));
    progress.advance();
  }
  table.error.subnets = static_cast<int>(check_set.size());
  for (int i = 0; i < table.error.subnets; ++i) {
    const double e = 100.0 * std::abs(table.error.predicted_ms[i] - table.error.measured_ms[i]) /
                     table.error.measured_ms[i];
    table.error.mean_abs_percent += e / table.error.subnets;
    table.error.max_abs_percent = std::max(table.error.max_abs_percent, e);
  }
  return table;
}

nlohmann::ordered_json to_json(const LatencyTable& t) {
  nlohmann::ordered_json conv = nlohmann::ordered_json::object();
  for (const auto& [key, ms] : t.conv_ms) conv[key] = ms;
  return {{"precision", t.precision},
          {"lr_size", {t.lr_width, t.lr_height}},
          {"threads", t.threads},
          {"calibration", {{"scale", t.scale}, {"element_ns", t.element_ns}, {"offset_ms", t.offset_ms}}},
          {"error",
           {{"subnets", t.error.subnets},
            {"mean_abs_percent", t.error.mean_abs_percent},
            {"max_abs_percent", t.error.max_abs_percent},
            {"predicted_ms", t.error.predicted_ms},
            {"measured_ms", t.error.measured_ms}}},
          {"conv_ms", conv}};
}

LatencyTable latency_table_from_json(const nlohmann::ordered_json& j, const std::string& context) {
  LatencyTable t;
  try {
    const auto size = j.at("lr_size").get<std::vector<int64_t>>();
    if (size.size() != 2 || size[0] < 1 || size[1] < 1) throw Error(context + ": lr_size", "expected [width, height]");
    if (j.contains("precision")) t.precision = j.at("precision").get<Precision>();  // absent: a float32 table
    t.lr_width = size[0];
    t.lr_height = size[1];
    t.threads = j.at("threads").get<int>();
    const auto& c = j.at("calibration");
    t.scale = c.at("scale").get<double>();
    t.element_ns = c.at("element_ns").get<double>();
    t.offset_ms = c.at("offset_ms").get<double>();
    const auto& e = j.at("error");
    t.error.subnets = e.at("subnets").get<int>();
    t.error.mean_abs_percent = e.at("mean_abs_percent").get<double>();
    t.error.max_abs_percent = e.at("max_abs_percent").get<double>();
    t.error.predicted_ms = e.at("predicted_ms").get<std::vector<double>>();
    t.error.measured_ms = e.at("measured_ms").get<std::vector<double>>();
    for (const auto& [key, ms] : j.at("conv_ms").items()) {
      const double v = ms.get<double>();
      if (!std::isfinite(v) || v < 0) throw Error(context + ": conv_ms." + key, "not a time");
      t.conv_ms[key] = v;
    }
  } catch (const nlohmann::json::exception& e) {
    throw Error(context, std::string("malformed latency table: ") + e.what());
  }
  return t;
}

std::string latency_table_key(Precision precision) {
  return precision == Precision::Fp32 ? "latency_table" : "latency_table_" + enum_name(precision);
}

std::map<Precision, LatencyTable> latency_tables_from(const nlohmann::ordered_json& extra, const std::string& context) {
  std::map<Precision, LatencyTable> tables;
  if (!extra.is_object()) return tables;
  for (const auto& name : EnumNames<Precision>::names()) {
    const Precision p = enum_from_name<Precision>(name);
    const std::string key = latency_table_key(p);
    if (!extra.contains(key)) continue;
    LatencyTable t = latency_table_from_json(extra.at(key), context + ": " + key);
    if (t.precision != p)
      throw Error(context + ": " + key, "holds a " + enum_name(t.precision) + " table, not " + name);
    tables.emplace(p, std::move(t));
  }
  return tables;
}

}  // namespace cgsr
