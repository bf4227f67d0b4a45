#pragma once
// Exporting a network: its inference graph (SRNetworkImpl::describe(false): the geometry head
// is left out) written as ONNX (onnx_writer.h) or TorchScript (torchscript_writer.h), with the
// spec and interface recorded in the file. Plain, CG-enhanced, searched and statically pruned
// models are all SRNetwork specs, so all of them export through their graph.
//
//   ExportOptions o;
//   o.format = ExportFormat::Onnx;  o.width = 320;  o.height = 240;
//   ExportedModel m = export_network(*net, "pan_x2.onnx", o);

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "export/export_format.h"
#include "export/export_signature.h"
#include "export/onnx_writer.h"
#include "models/sr_network.h"

namespace cgsr {

struct ExportOptions {
  ExportFormat format = ExportFormat::Onnx;
  int64_t width = 0, height = 0;  // LR input size: fixed in an ONNX file unless dynamic_size
  bool dynamic_size = false;      // ONNX: symbolic batch/height/width (TorchScript is always size-free)
  CubicResize cubic = CubicResize::Conv;  // ONNX: how a bicubic resize is written
  std::optional<Calibration> int8;        // ONNX: quantized (QDQ) with these ranges; recorded in the file
};

struct ExportedModel {
  std::filesystem::path file;
  ExportFormat format = ExportFormat::Onnx;
  ExportSignature signature;
  int64_t width = 0, height = 0;
  bool dynamic_size = false;
  uintmax_t bytes = 0;
};

// Key/value pairs describing a network (spec YAML, summary, scale, rendering channels), stored
// as ONNX metadata_props and as TorchScript extra files.
std::vector<std::pair<std::string, std::string>> export_metadata(const SRNetworkImpl& net);

// Writes `graph` to `out` atomically (ONNX files are then checked). `metadata` as above.
ExportedModel export_graph(const graph::Graph& graph, const std::filesystem::path& out, const ExportOptions& options,
                           const std::vector<std::pair<std::string, std::string>>& metadata = {});

ExportedModel export_network(const SRNetworkImpl& net, const std::filesystem::path& out, const ExportOptions& options);

}  // namespace cgsr
