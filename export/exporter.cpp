#include "export/exporter.h"

#include <torch/torch.h>

#include "core/error.h"
#include "core/text.h"
#include "export/torchscript_writer.h"
#include "models/arch_spec.h"

namespace cgsr {

const std::vector<std::string>& EnumNames<ExportFormat>::names() {
  static const std::vector<std::string> names = {"onnx", "torchscript"};
  return names;
}

std::vector<std::pair<std::string, std::string>> export_metadata(const SRNetworkImpl& net) {
  const ArchSpec& spec = net.spec();
  std::vector<std::pair<std::string, std::string>> m = {
      {"cgsr.summary", spec_summary(spec)},
      {"cgsr.scale", std::to_string(spec.scale)},
      {"cgsr.spec", spec_to_yaml(spec)},
  };
  if (net.has_rit()) {
    m.emplace_back("cgsr.render_channels", join(spec.rit.channels));
    m.emplace_back("cgsr.render_info_size", spec.rit.reads_hr() ? "hr" : "lr");
    m.emplace_back("cgsr.depth_encoding", enum_name(spec.rit.depth_encoding));
  }
  return m;
}

ExportedModel export_graph(const graph::Graph& graph, const std::filesystem::path& out, const ExportOptions& options,
                           const std::vector<std::pair<std::string, std::string>>& metadata) {
  if (out.empty()) throw Error("export", "no output file given");
  ExportedModel exported;
  exported.file = out;
  exported.format = options.format;
  exported.signature = export_signature(graph);
  exported.width = options.width;
  exported.height = options.height;
  exported.dynamic_size = options.format == ExportFormat::TorchScript || options.dynamic_size;
  if (options.int8 && options.format != ExportFormat::Onnx)
    throw Error("export", "int8 is exported as ONNX (QuantizeLinear/DequantizeLinear), not " + enum_name(options.format));
  if (options.format == ExportFormat::Onnx) {
    OnnxOptions o;
    o.width = options.width;
    o.height = options.height;
    o.dynamic_size = options.dynamic_size;
    o.cubic = options.cubic;
    o.metadata = metadata;
    o.int8 = options.int8;
    o.metadata.emplace_back("cgsr.precision", options.int8 ? "int8" : "fp32");
    if (options.int8) o.metadata.emplace_back("cgsr.calibration", calibration_json(*options.int8).dump());
    write_onnx(out, graph, o);
  } else {
    TorchScriptOptions o;
    for (const auto& [key, value] : metadata) o.extra_files.emplace_back(key, value);
    write_torchscript(out, graph, o);
  }
  exported.bytes = std::filesystem::file_size(out);
  return exported;
}

ExportedModel export_network(const SRNetworkImpl& net, const std::filesystem::path& out, const ExportOptions& options) {
  try {
    return export_graph(net.describe(/*training=*/false), out, options, export_metadata(net));
  } catch (const Error& e) {
    throw e.within(spec_summary(net.spec()));
  }
}

}  // namespace cgsr
