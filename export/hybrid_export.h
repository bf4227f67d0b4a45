#pragma once
// Exporting a hybrid-pruned model (pruning/hybrid_model.h) for a game engine: one network file
// per pattern, the selector (the dynamic pruning component, selector_onnx.h) as a small ONNX
// file, and manifest.json saying how they fit together, all in one directory:
//
//   DIR/pattern_0.onnx ... pattern_<K-1>.onnx   (.pt for TorchScript) the pool's patterns, widest first
//   DIR/selector.onnx                           picks the pattern of a frame
//   DIR/manifest.json                           inputs, files, cost and latency per pattern
//
// docs/deploying_hybrid.md describes the manifest's keys and the per-frame loop.
//
//   HybridExport e = export_hybrid(load_hybrid_model("pruned.cgsr"), "deploy/", options);

#include <filesystem>
#include <nlohmann/json.hpp>
#include <vector>

#include "export/exporter.h"
#include "pruning/hybrid_model.h"

namespace cgsr {

inline constexpr int kHybridManifestVersion = 1;
inline constexpr const char* kHybridManifestFile = "manifest.json";
inline constexpr const char* kSelectorFile = "selector.onnx";

struct HybridExport {
  std::filesystem::path dir, manifest_file, selector_file;
  std::vector<ExportedModel> patterns;  // [k]
  nlohmann::ordered_json manifest;
};

// The pattern file name of pattern k: pattern_<k>.onnx or pattern_<k>.pt.
std::string pattern_file_name(int k, ExportFormat format);

// Writes the directory (created if missing; existing files of these names are replaced). The
// ONNX files have options.width x options.height fixed; a size-free export is an error (the
// selector pools a fixed frame size). Errors name the directory or file.
HybridExport export_hybrid(const HybridModel& model, const std::filesystem::path& dir, const ExportOptions& options);

// The same from a model file; a file that is not a hybrid-pruned model is a cgsr::Error naming it.
HybridExport export_hybrid_file(const std::filesystem::path& model_file, const std::filesystem::path& dir,
                                const ExportOptions& options);

}  // namespace cgsr
