#include "pipeline/bench.h"

#include <torch/torch.h>

#include <algorithm>
#include <cstdio>

#include "core/error.h"
#include "core/runtime.h"
#include "core/tensor_checks.h"
#include "core/text.h"
#include "export/export_signature.h"
#include "export/onnx_writer.h"
#include "export/onnxruntime_runner.h"
#include "models/complexity.h"
#include "models/fused_graph.h"
#include "models/inference.h"
#include "models/model_source.h"

namespace cgsr {

config::Schema<BenchOptions> bench_schema() {
  config::Schema<BenchOptions> s;
  s.field("model", &BenchOptions::model, "backbone name, spec YAML file or model file to time");
  s.field("scale", &BenchOptions::scale, "scale for a backbone name (0: 2, or the file's)")
      .check([](int v) { return v == 0 || (v >= 2 && v <= 4); }, "must be 0, 2, 3 or 4");
  s.field("input", &BenchOptions::input, "LR input size WxH");
  s.field("batch", &BenchOptions::batch, "images per run").range(1, 64);
  s.field("warmup", &BenchOptions::warmup, "untimed runs first").range(0, 1000);
  s.field("runs", &BenchOptions::runs, "timed runs").range(1, 100000);
  s.field("engine", &BenchOptions::engine, "inference engine: fused (oneDNN) or libtorch");
  s.field("precisions", &BenchOptions::precisions, "number formats of the fused engine: fp32, bf16, int8");
  s.field("layout", &BenchOptions::layout, "activation memory layout of the libtorch engine");
  s.field("layers", &BenchOptions::layers, "also time every layer of the network");
  s.field("json", &BenchOptions::json, "print JSON instead of a table");
  s.field("onnx", &BenchOptions::onnx, "exported ONNX file to time in ONNX Runtime next to our forward pass");
  s.validate([](const BenchOptions& o, const config::Cursor& at, const YAML::Node& node) {
    if (o.model.empty() && o.onnx.empty())
      at.child("model").fail(node, "nothing to time: give --model NAME_OR_FILE and/or --onnx FILE");
    if (o.precisions.empty()) at.child("precisions").fail(node, "give at least one precision");
    if (o.engine != InferenceEngine::Fused && o.precisions != std::vector<Precision>{Precision::Fp32})
      at.child("precisions").fail(node, "only the fused engine runs in reduced precision");
  });
  add_run_settings(s);
  return s;
}

ModelSource bench_source(const BenchOptions& options) {
  if (!options.model.empty()) return resolve_model(options.model, options.scale);
  const std::string spec_yaml = inspect_onnx_file(options.onnx).metadata_value("cgsr.spec");
  if (spec_yaml.empty())
    throw Error(options.onnx, "records no cgsr spec (not written by cgsr export): give --model for our side");
  ModelSource source;
  source.kind = ModelSource::Kind::SpecFile;
  source.origin = options.onnx;
  source.spec = spec_from_yaml(spec_yaml, options.onnx + " (cgsr.spec)");
  source.network = SRNetwork(source.spec);
  return source;
}

BenchResult time_onnx(const BenchOptions& options) {
  const auto [w, h] = parse_size(options.input, "--input");
  ModelSource source = bench_source(options);
  const ExportSignature signature = export_signature(source.network->describe());
  const NamedTensors inputs = random_inputs(signature, w, h, /*seed=*/1, options.batch);
  // The file must be an export of this model (when it says which), take what the model takes,
  // at this size unless its size is symbolic.
  const OnnxModelInfo info = inspect_onnx_file(options.onnx);
  if (const std::string recorded = info.metadata_value("cgsr.spec"); !recorded.empty()) {
    const ArchSpec spec = spec_from_yaml(recorded, options.onnx + " (cgsr.spec)");
    if (spec != source.spec)
      throw Error(options.onnx, "is an export of " + spec_summary(spec) + ", not of " + spec_summary(source.spec) +
                                    " (--model " + options.model + ")");
  }
  for (const auto& [name, t] : inputs) {
    const OnnxTensorInfo* declared = info.find_input(name);
    if (!declared || declared->dims.size() != 4)
      throw Error(options.onnx, "has no 4-D input '" + name + "' but " + spec_summary(source.spec) + " takes one");
    for (size_t d = 0; d < 4; ++d)
      if (declared->dims[d].value >= 0 && declared->dims[d].value != t.size(static_cast<int64_t>(d)))
        throw Error(options.onnx, "input '" + name + "' is fixed at another size than " + shape_string(t) +
                                      " (--input " + options.input + ", --batch " + std::to_string(options.batch) +
                                      "): bench it with its own --input or export it with --dynamic-size");
  }
  if (info.inputs.size() != inputs.size())
    throw Error(options.onnx, "takes " + std::to_string(info.inputs.size()) + " inputs, " +
                                  spec_summary(source.spec) + " takes " + std::to_string(inputs.size()));
  const OnnxRuntimeRunner runner(thread_count());
  const auto result = runner.run_checked({{options.onnx, {{inputs, options.warmup, options.runs}}}});
  const std::vector<double>& ms = result.at(0).runs.at(0).times_ms;
  BenchResult r;
  r.target.name = std::filesystem::path(options.onnx).filename().string();
  r.target.runtime = "onnxruntime";
  r.target.detail = "ORT " + runner.version();
  r.target.macs = complexity(*source.network, w, h).macs * options.batch;
  r.latency = summarize_latency(ms);
  r.gflops = r.latency.median_ms > 0 ? 2.0 * static_cast<double>(r.target.macs) / (r.latency.median_ms * 1e6) : 0.0;
  return r;
}

BenchTarget model_target(const BenchOptions& options, Precision precision) {
  const auto [w, h] = parse_size(options.input, "--input");
  ModelSource source = bench_source(options);
  SRNetwork net = source.network;
  const auto color = torch::rand({options.batch, 3, h, w});
  torch::Tensor info;
  if (net->has_rit()) {
    const int64_t f = net->rit()->info_factor();
    info = torch::rand({options.batch, static_cast<int64_t>(source.spec.rit.info_width()), h * f, w * f});
  }
  BenchTarget t;
  t.name = spec_summary(source.spec);
  t.macs = complexity(*net, w, h).macs * options.batch;
  if (options.engine == InferenceEngine::Fused) {
    net->eval();
    const graph::Graph g = net->describe();
    FusedGraph::Options fused_options;
    fused_options.precision = precision;
    if (precision == Precision::Int8)
      fused_options.calibration = calibrate(g, {network_inputs(g, color, info)}, CalibrationMethod::Max);
    auto fused = std::make_shared<FusedGraph>(g, fused_options);
    t.runtime = "cgsr fused";
    t.detail = "oneDNN " + enum_name(precision);
    t.run = [fused, color, info] { fused->run(color, info); };
    return t;
  }
  const MemoryLayout layout = inference_layout(*net, color, info, options.layout);
  t.runtime = "libtorch";
  t.detail = std::string("layout ") + enum_name(layout);
  t.run = [net, color, info, layout]() mutable { infer(*net, color, info, layout); };
  return t;
}

nlohmann::ordered_json layer_profile(const BenchOptions& options) {
  const auto [w, h] = parse_size(options.input, "--input");
  ModelSource source = bench_source(options);
  SRNetwork net = source.network;
  net->eval();
  torch::NoGradGuard no_grad;
  const graph::Graph g = net->describe();
  torch::Tensor info;
  if (net->has_rit()) {
    const int64_t f = net->rit()->info_factor();
    info = torch::rand({options.batch, source.spec.rit.info_width(), h * f, w * f});
  }
  const auto inputs = network_inputs(g, torch::rand({options.batch, 3, h, w}), info);
  std::vector<double> total(g.ops.size(), 0.0), once;
  for (int i = 0; i < options.warmup; ++i) graph::run(g, inputs);
  for (int i = 0; i < options.runs; ++i) {
    graph::run(g, inputs, &once);
    for (size_t k = 0; k < once.size(); ++k) total[k] += once[k];
  }
  const Complexity cost = complexity(g, w, h);
  std::vector<size_t> order(g.ops.size());
  for (size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return total[a] > total[b]; });
  double sum = 0;
  for (double t : total) sum += t;
  auto rows = nlohmann::ordered_json::array();
  for (size_t k : order) {
    const auto& op = g.ops[k];
    int64_t macs = 0;
    for (const auto& l : cost.layers)
      if (l.name == op.name) macs = l.macs * options.batch;
    const double ms = total[k] / options.runs;
    rows.push_back({{"name", op.name},
                    {"kind", graph::op_kind_name(op.kind)},
                    {"ms", ms},
                    {"share", sum > 0 ? total[k] / sum : 0.0},
                    {"macs", macs},
                    {"gflops", ms > 0 ? 2.0 * static_cast<double>(macs) / (ms * 1e6) : 0.0}});
  }
  return rows;
}

BenchResult time_target(const BenchTarget& target, int warmup, int runs) {
  BenchResult r;
  r.target = target;
  r.latency = measure_latency(target.run, warmup, runs);
  r.gflops = r.latency.median_ms > 0 ? 2.0 * static_cast<double>(target.macs) / (r.latency.median_ms * 1e6) : 0.0;
  return r;
}

nlohmann::ordered_json run_bench(const BenchOptions& options) {
  std::vector<BenchTarget> targets;
  for (Precision p : options.precisions) targets.push_back(model_target(options, p));
  nlohmann::ordered_json results;
  results["input"] = options.input;
  results["batch"] = options.batch;
  results["threads"] = thread_count();
  results["warmup"] = options.warmup;
  results["runs"] = options.runs;
  std::vector<BenchResult> timed;
  for (const auto& t : targets) timed.push_back(time_target(t, options.warmup, options.runs));
  if (!options.onnx.empty()) {
    timed.push_back(time_onnx(options));
    results["onnxruntime_vs_cgsr"] = timed.back().latency.median_ms / timed.front().latency.median_ms;
  }
  // Each reduced precision against float32 on the same input in the same run.
  const auto fp32 = std::find(options.precisions.begin(), options.precisions.end(), Precision::Fp32);
  if (fp32 != options.precisions.end() && options.precisions.size() > 1) {
    const double base = timed[static_cast<size_t>(fp32 - options.precisions.begin())].latency.median_ms;
    for (size_t i = 0; i < options.precisions.size(); ++i)
      if (options.precisions[i] != Precision::Fp32)
        results["speedup_vs_fp32"][enum_name(options.precisions[i])] = base / timed[i].latency.median_ms;
  }
  auto rows = nlohmann::ordered_json::array();
  for (const auto& r : timed)
    rows.push_back({{"name", r.target.name},
                    {"runtime", r.target.runtime},
                    {"detail", r.target.detail},
                    {"macs", r.target.macs},
                    {"median_ms", r.latency.median_ms},
                    {"min_ms", r.latency.min_ms},
                    {"max_ms", r.latency.max_ms},
                    {"gflops", r.gflops}});
  results["results"] = rows;
  if (options.layers) results["layers"] = layer_profile(options);
  if (options.json) {
    std::printf("%s\n", results.dump(2).c_str());
    return results;
  }
  std::printf("input %s x%d, %d threads, %d warm-up + %d timed runs\n", options.input.c_str(), options.batch,
              thread_count(), options.warmup, options.runs);
  std::printf("%-40s %-11s %-12s %10s %9s %9s %9s %9s\n", "model", "runtime", "detail", "median ms", "min ms", "max ms",
              "GFLOP/s", "MACs");
  for (const auto& r : timed)
    std::printf("%-40s %-11s %-12s %10.2f %9.2f %9.2f %9.1f %9s\n", r.target.name.c_str(), r.target.runtime.c_str(),
                r.target.detail.c_str(), r.latency.median_ms, r.latency.min_ms, r.latency.max_ms, r.gflops,
                format_count(static_cast<double>(r.target.macs)).c_str());
  if (results.contains("onnxruntime_vs_cgsr"))
    std::printf("ONNX Runtime median / our median: %.2fx\n", results["onnxruntime_vs_cgsr"].get<double>());
  if (results.contains("speedup_vs_fp32"))
    for (const auto& [name, ratio] : results["speedup_vs_fp32"].items())
      std::printf("fp32 median / %s median: %.2fx\n", name.c_str(), ratio.get<double>());
  if (options.layers) {
    std::printf("\nper layer (graph interpreter, NCHW, mean of %d runs; slowest first)\n", options.runs);
    std::printf("%-44s %-14s %9s %7s %9s %9s\n", "layer", "kind", "ms", "share", "GFLOP/s", "MACs");
    for (const auto& l : results["layers"])
      std::printf("%-44s %-14s %9.3f %6.1f%% %9.1f %9s\n", l["name"].get<std::string>().c_str(),
                  l["kind"].get<std::string>().c_str(), l["ms"].get<double>(), 100.0 * l["share"].get<double>(),
                  l["gflops"].get<double>(), format_count(static_cast<double>(l["macs"].get<int64_t>())).c_str());
  }
  return results;
}

}  // namespace cgsr
