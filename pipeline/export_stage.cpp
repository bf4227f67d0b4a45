#include "pipeline/export_stage.h"

#include <torch/torch.h>

#include <cstdio>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/runtime.h"
#include "core/text.h"
#include "export/exporter.h"
#include "export/hybrid_export.h"
#include "export/hybrid_verification.h"
#include "export/onnx_writer.h"
#include "export/verification.h"
#include "models/arch_spec.h"
#include "models/complexity.h"
#include "models/fused_graph.h"
#include "models/model_source.h"
#include "pruning/hybrid_model.h"
#include "render_data/dataset.h"
#include "render_data/patch_sampler.h"

namespace cgsr {

config::Schema<ExportCommandOptions> export_schema() {
  config::Schema<ExportCommandOptions> s;
  s.field("model", &ExportCommandOptions::model, "backbone name, spec YAML file or model file to export").required();
  s.field("scale", &ExportCommandOptions::scale, "scale for a backbone name (0: 2, or the file's)")
      .check([](int v) { return v == 0 || (v >= 2 && v <= 4); }, "must be 0, 2, 3 or 4");
  s.field("format", &ExportCommandOptions::format, "file format");
  s.field("input", &ExportCommandOptions::input, "LR input size WxH");
  s.field("dynamic_size", &ExportCommandOptions::dynamic_size, "ONNX: symbolic batch, height and width");
  s.field("cubic_resize", &ExportCommandOptions::cubic_resize,
          "ONNX: bicubic resize as a fixed conv (runs everywhere) or a native cubic Resize");
  s.field("verify", &ExportCommandOptions::verify, "verify the file in other runtimes against our forward pass");
  s.field("tolerance", &ExportCommandOptions::tolerance, "max abs error allowed by verify").range(0, 1);
  s.field("out", &ExportCommandOptions::out, "the file to write (a directory for a hybrid-pruned model)").required();
  s.field("precision", &ExportCommandOptions::precision,
          "fp32, or int8: ONNX with QuantizeLinear/DequantizeLinear around the convolutions, calibrated on data");
  s.field("data", &ExportCommandOptions::data,
          "data set whose rendered frames calibrate int8's activations and, with verify, verify the file");
  s.field("frames", &ExportCommandOptions::frames,
          "verify: frame range A:B of data (A included, B not) run in order; empty = the first test frame")
      .check([](const std::string& v) { return v.empty() || parse_frame_range(v).has_value(); },
             "must be A:B with whole numbers 0 <= A < B");
  s.section("calibration", &ExportCommandOptions::calibration, calibration_schema_fields(),
            "int8: the frames activation ranges are measured on");
  s.field("int8_tolerance", &ExportCommandOptions::int8_tolerance,
          "int8: max abs error allowed by verify against the fused path's int8 output")
      .range(0, 1);
  const auto fp32 = [](const ExportCommandOptions& o) { return o.precision == Precision::Fp32; };
  for (const char* key : {"precision", "calibration", "int8_tolerance"}) s.omit_when(key, fp32);
  s.omit_when("data", [](const ExportCommandOptions& o) { return o.data.empty(); });
  s.omit_when("frames", [](const ExportCommandOptions& o) { return o.frames.empty(); });
  s.validate([](const ExportCommandOptions& o, const config::Cursor& at, const YAML::Node& node) {
    parse_size(o.input, "input");
    if (o.dynamic_size && o.format != ExportFormat::Onnx)
      at.child("dynamic_size").fail(node, "only ONNX files have a fixed size; a TorchScript file takes any size");
    if (o.precision == Precision::Bf16)
      at.child("precision").fail(node, "bf16 is not exported: export fp32 and let the runtime convert");
    if (o.precision == Precision::Int8 && o.format != ExportFormat::Onnx)
      at.child("precision").fail(node, "int8 is exported as ONNX (format: onnx)");
    if (o.precision == Precision::Int8 && o.data.empty())
      at.child("data").fail(node, "int8 needs a data set to calibrate its activations on (--data DIR)");
    if (!o.frames.empty() && (o.data.empty() || !o.verify))
      at.child("frames").fail(node, "frames are verified on: give --verify and the data set (--data DIR)");
  });
  add_run_settings(s);
  return s;
}

namespace {

// Prints the verification table and turns failures into errors naming `what`.
void report_verification(const VerifyReport& report, double tolerance, const std::string& what) {
  std::printf("\n%s", report.table().c_str());
  std::printf("verification: %d passed, %d failed, %d skipped (tolerance %g)\n", report.passed(), report.failed(),
              report.skipped(), tolerance);
  if (report.failed() > 0)
    throw Error(what, "verification failed: " + std::to_string(report.failed()) + " of " +
                          std::to_string(report.checks.size()) +
                          " checks did not run or did not match our forward pass",
                ErrorKind::Internal);
  if (!report.ok()) throw Error(what, "verification could not run: every runtime was skipped (see above)");
}

// A hybrid-pruned model: a directory of pattern files, the selector and the manifest.
nlohmann::ordered_json run_hybrid_export(const ExportCommandOptions& options, const ExportOptions& o) {
  const HybridModel model = load_hybrid_model(options.model);
  const HybridExport exported = export_hybrid(model, options.out, o);
  nlohmann::ordered_json results;
  results["model"] = exported.manifest.at("model");
  results["hybrid"] = true;
  results["dir"] = exported.dir.string();
  results["manifest"] = exported.manifest_file.string();
  results["format"] = enum_name(o.format);
  std::printf("%s: hybrid-pruned %s, %d patterns (%s) + selector\n", exported.dir.string().c_str(),
              exported.manifest.at("model").get<std::string>().c_str(), static_cast<int>(exported.patterns.size()),
              enum_name(o.format).c_str());
  std::printf("  %s\n", signature_string(exported.patterns.front().signature, o.width, o.height).c_str());
  std::printf("  %-16s %8s %10s %10s %10s\n", "file", "channels", "MACs", "KiB", "latency");
  auto files = nlohmann::ordered_json::array();
  const auto& entries = exported.manifest.at("patterns");
  for (size_t k = 0; k < exported.patterns.size(); ++k) {
    const auto& e = entries.at(k);
    char latency[32] = "-";
    if (!e.at("latency_ms").is_null()) std::snprintf(latency, sizeof latency, "%.2f ms", e.at("latency_ms").get<double>());
    std::printf("  %-16s %7.0f%% %10s %10.1f %10s\n", e.at("file").get<std::string>().c_str(),
                100.0 * e.at("channel_fraction").get<double>(), format_count(e.at("macs").get<double>()).c_str(),
                static_cast<double>(exported.patterns[k].bytes) / 1024.0, latency);
    files.push_back({{"file", exported.patterns[k].file.string()}, {"bytes", exported.patterns[k].bytes}});
  }
  const auto selector_bytes = std::filesystem::file_size(exported.selector_file);
  std::printf("  %-16s %8s %10s %10.1f\n", kSelectorFile, "-",
              format_count(exported.manifest.at("selector").at("macs").get<double>()).c_str(),
              static_cast<double>(selector_bytes) / 1024.0);
  files.push_back({{"file", exported.selector_file.string()}, {"bytes", selector_bytes}});
  results["files"] = files;
  const OnnxModelInfo selector = inspect_onnx_file(exported.selector_file);
  std::vector<std::string> ops;
  for (const auto& [type, count] : selector.op_counts) ops.push_back(type + " " + std::to_string(count));
  std::printf("  selector: opset %lld, ONNX checker ok; %s\n", static_cast<long long>(selector.opset), join(ops).c_str());
  std::printf("  manifest: %s\n", exported.manifest_file.string().c_str());
  // results.json sits beside the files (also when verification fails, so the failure is on record).
  const auto results_file = exported.dir / "results.json";
  if (!options.verify) {
    write_file_atomic(results_file, results.dump(2) + "\n");
    return results;
  }
  VerifyOptions v;
  v.tolerance = options.tolerance;
  const uint64_t seed = make_rng("export-verify")();
  const VerifyReport report = verify_hybrid_export(model, exported, v, seed);
  results["verification"] = report.to_json();
  write_file_atomic(results_file, results.dump(2) + "\n");
  report_verification(report, options.tolerance, exported.dir.string());
  return results;
}

// The frames of `data` that verify a file: `range` in order (a sequence keeps its history, reset
// at scene cuts, as the data set derives it), or the first test frame.
std::vector<int> verification_frames(const Dataset& data, const std::string& range) {
  if (range.empty()) {
    const std::vector<int> test = data.frames(Split::Test);
    return {test.empty() ? 0 : test.front()};
  }
  const auto [first, end] = *parse_frame_range(range);
  const int n = data.frame_count();
  if (end > n)
    throw Error(data.info().root.string(), "frames " + range + ": the data set has " + std::to_string(n) +
                                               " frames (0:" + std::to_string(n) + ")");
  std::vector<int> frames;
  for (int f = first; f < end; ++f) frames.push_back(f);
  return frames;
}

}  // namespace

nlohmann::ordered_json run_export(const ExportCommandOptions& options) {
  const auto [w, h] = parse_size(options.input, "--input");
  ExportOptions o;
  o.format = options.format;
  o.width = w;
  o.height = h;
  o.dynamic_size = options.dynamic_size;
  o.cubic = options.cubic_resize;
  ModelSource source = resolve_model(options.model, options.scale);
  if (source.provenance && is_hybrid_model(*source.provenance)) {
    if (options.precision != Precision::Fp32) throw Error(options.model, "a hybrid-pruned model exports in fp32 only");
    if (!options.frames.empty())
      throw Error(options.model, "a hybrid-pruned model verifies on random inputs and sampler frames, not on --frames");
    return run_hybrid_export(options, o);
  }
  SRNetwork net = source.network;
  net->eval();
  std::optional<Dataset> data;
  if (!options.data.empty() && (options.precision == Precision::Int8 || options.verify))
    data = open_for_channels(options.data, net->input_channels());
  if (options.precision == Precision::Int8) o.int8 = calibrate_network(*net, *data, options.calibration);
  const ExportedModel exported = export_network(*net, options.out, o);

  nlohmann::ordered_json results;
  results["model"] = spec_summary(source.spec);
  results["file"] = exported.file.string();
  results["format"] = enum_name(exported.format);
  results["precision"] = enum_name(options.precision);
  results["bytes"] = exported.bytes;
  results["dynamic_size"] = exported.dynamic_size;
  results["signature"] = exported.dynamic_size ? signature_string(exported.signature, w, h) + " (any size)"
                                               : signature_string(exported.signature, w, h);
  std::printf("%s: %s, %s\n", exported.file.string().c_str(), results["model"].get<std::string>().c_str(),
              enum_name(exported.format).c_str());
  std::printf("  %s\n", results["signature"].get<std::string>().c_str());
  if (exported.format == ExportFormat::Onnx) {
    const OnnxModelInfo info = inspect_onnx_file(exported.file);
    std::vector<std::string> ops;
    for (const auto& [type, count] : info.op_counts) {
      ops.push_back(type + " " + std::to_string(count));
      results["onnx_ops"][type] = count;
    }
    results["opset"] = info.opset;
    std::printf("  opset %lld, ONNX checker ok; %s\n", static_cast<long long>(info.opset), join(ops).c_str());
  }
  std::printf("  %.1f KiB\n", static_cast<double>(exported.bytes) / 1024.0);
  if (!options.verify) return results;

  // Random frames at the export size, and for size-free files also at a second, odd size.
  std::vector<std::pair<int64_t, int64_t>> sizes = {{w, h}};
  if (exported.dynamic_size) sizes.emplace_back(w / 2 + 3, h / 2 + 1);
  VerifyOptions v;
  v.tolerance = o.int8 ? options.int8_tolerance : options.tolerance;
  const uint64_t seed = make_rng("export-verify")();
  // INT8 is compared with the fused path's INT8 run with the same calibration, on the random
  // inputs and on a rendered frame (calibrated ranges fit rendered frames, not noise).
  ReferenceForward forward;
  if (o.int8) {
    FusedGraph::Options fused;
    fused.precision = Precision::Int8;
    fused.calibration = *o.int8;
    auto int8 = std::make_shared<FusedGraph>(net->describe(), fused);
    forward = [int8](const torch::Tensor& color, const torch::Tensor& info) { return int8->run(color, info); };
  }
  VerifyCase c = make_verify_case(*net, exported, sizes, seed, forward);
  if (data) {
    // A recurrent network's state: its output for the frame before, as cgsr computed it; none at a
    // scene's first frame (a cut), as an engine resets it.
    torch::Tensor previous;
    int previous_frame = -1;
    for (int frame : verification_frames(*data, options.frames)) {
      const Batch b = frame_batch(*data, frame, net->spec().scale, net->input_channels(), net->depth_encoding());
      const bool follows = previous.defined() && previous_frame == frame - 1 && data->has_previous(frame);
      const int64_t fw = b.lr_color.size(3), fh = b.lr_color.size(2);
      if (!exported.dynamic_size && (fw != w || fh != h)) {
        // The first test frame is a bonus check; frames asked for must run.
        if (options.frames.empty()) break;
        throw Error(options.data, "frame " + std::to_string(frame) + " is " + std::to_string(fw) + "x" +
                                      std::to_string(fh) + " at LR, the file takes " + options.input +
                                      " (--input, or --dynamic-size)");
      }
      add_verify_inputs(c, *net, inputs_from_batch(*net, b, follows ? previous : torch::Tensor()), forward,
                        "frame " + std::to_string(frame));
      previous = c.expected.back();
      previous_frame = frame;
    }
  }
  const VerifyReport report = verify_exports({c}, v);
  results["verification"] = report.to_json();
  report_verification(report, v.tolerance, exported.file.string());
  return results;
}

}  // namespace cgsr
