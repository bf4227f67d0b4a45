#include "cli/commands/export.h"

#include <torch/torch.h>

#include <cstdio>

#include "core/error.h"
#include "core/runtime.h"
#include "core/text.h"
#include "export/exporter.h"
#include "export/onnx_writer.h"
#include "export/verification.h"
#include "models/arch_spec.h"
#include "models/model_source.h"

namespace cgsr::cli {

config::Schema<ExportCommandOptions> export_schema() {
  config::Schema<ExportCommandOptions> s;
  s.field("model", &ExportCommandOptions::model, "backbone name, spec YAML file or model file to export").required();
  s.field("scale", &ExportCommandOptions::scale, "scale for a backbone name (0: 2, or the file's)")
      .check([](int v) { return v == 0 || (v >= 2 && v <= 4); }, "must be 0, 2, 3 or 4");
  s.field("format", &ExportCommandOptions::format, "file format");
  s.field("input", &ExportCommandOptions::input, "LR input size WxH");
  s.field("dynamic_size", &ExportCommandOptions::dynamic_size, "ONNX: symbolic batch, height and width");
  s.field("cubic_resize", &ExportCommandOptions::cubic_resize,
          "ONNX: bicubic resize as a fixed conv (runs everywhere) or a native cubic Resize")
      .one_of({"conv", "native"});
  s.field("verify", &ExportCommandOptions::verify, "verify the file in other runtimes against our forward pass");
  s.field("tolerance", &ExportCommandOptions::tolerance, "max abs error allowed by verify").range(0, 1);
  s.field("out", &ExportCommandOptions::out, "the file to write").required();
  s.validate([](const ExportCommandOptions& o, const config::Cursor& at, const YAML::Node& node) {
    parse_size(o.input, "input");
    if (o.dynamic_size && o.format != ExportFormat::Onnx)
      at.child("dynamic_size").fail(node, "only ONNX files have a fixed size; a TorchScript file takes any size");
  });
  add_run_settings(s);
  return s;
}

void setup_export(CLI::App& app) {
  add_command<ExportCommandOptions>(
      app, "export", "Export a network as ONNX or TorchScript, optionally verified in other runtimes", export_schema,
      [](CLI::App& sub, std::vector<FlagAssignment>& flags) {
        flag_to_key(sub, flags, "--model", "model", "backbone name, spec YAML file or model file");
        flag_to_key(sub, flags, "--scale", "scale", "scale for a backbone name");
        flag_to_key(sub, flags, "--format", "format", "onnx or torchscript");
        flag_to_key(sub, flags, "--input", "input", "LR input size WxH");
        switch_to_key(sub, flags, "--dynamic-size", "dynamic_size", "ONNX: symbolic batch, height and width");
        flag_to_key(sub, flags, "--cubic-resize", "cubic_resize", "ONNX bicubic resize: conv or native");
        switch_to_key(sub, flags, "--verify", "verify", "verify in other runtimes against our forward pass");
        flag_to_key(sub, flags, "--tolerance", "tolerance", "max abs error allowed by --verify");
        flag_to_key(sub, flags, "--out", "out", "the file to write");
      },
      [](const ExportCommandOptions& options, const YAML::Node&, RunDir*) { return run_export(options); },
      /*always_run_dir=*/false);
}

nlohmann::ordered_json run_export(const ExportCommandOptions& options) {
  const auto [w, h] = parse_size(options.input, "--input");
  ModelSource source = resolve_model(options.model, options.scale);
  SRNetwork net = source.network;
  net->eval();

  ExportOptions o;
  o.format = options.format;
  o.width = w;
  o.height = h;
  o.dynamic_size = options.dynamic_size;
  o.cubic = cubic_resize_from_name(options.cubic_resize);
  const ExportedModel exported = export_network(*net, options.out, o);

  nlohmann::ordered_json results;
  results["model"] = spec_summary(source.spec);
  results["file"] = exported.file.string();
  results["format"] = enum_name(exported.format);
  results["bytes"] = exported.bytes;
  results["dynamic_size"] = exported.dynamic_size;
  results["signature"] = exported.dynamic_size ? signature_string(exported.signature, w, h) + " (any size)"
                                               : signature_string(exported.signature, w, h);
  std::printf("%s: %s, %s\n", exported.file.string().c_str(), results["model"].get<std::string>().c_str(),
              enum_name(exported.format));
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
  v.tolerance = options.tolerance;
  const uint64_t seed = make_rng("export-verify")();
  const VerifyReport report = verify_exports({make_verify_case(*net, exported, sizes, seed)}, v);
  std::printf("\n%s", report.table().c_str());
  std::printf("verification: %d passed, %d failed, %d skipped (tolerance %g)\n", report.passed(), report.failed(),
              report.skipped(), options.tolerance);
  results["verification"] = report.to_json();
  if (report.failed() > 0)
    throw Error(exported.file.string(), "verification failed: " + std::to_string(report.failed()) + " of " +
                                            std::to_string(report.checks.size()) +
                                            " checks did not run or did not match our forward pass",
                ErrorKind::Internal);
  if (!report.ok())
    throw Error(exported.file.string(), "verification could not run: every runtime was skipped (see above)");
  return results;
}

}  // namespace cgsr::cli
