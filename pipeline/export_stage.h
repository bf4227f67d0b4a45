#pragma once
// The export job: what `cgsr export` runs, and the export stage of `cgsr run` (once per model
// and format). Writes a network as ONNX or TorchScript for other runtimes, optionally verified
// in them (export/verification.h).
//
//   cgsr export --model pan --scale 2 --format onnx --input 320x240 --out pan_x2.onnx --verify
//   cgsr export --model runs/train/model.cgsr --format torchscript --out model.pt
//   cgsr export --model runs/train/model.cgsr --input 320x240 --verify --data DIR --frames 40:48
//
// `out` names the exported file (the job writes no run directory). A hybrid-pruned model
// file (pruning/hybrid_model.h) exports as a directory instead: `out` DIR gets one file per
// pattern, selector.onnx, manifest.json and results.json (export/hybrid_export.h).

#include <nlohmann/json.hpp>
#include <string>

#include "export/export_format.h"
#include "eval/calibration.h"
#include "export/onnx_writer.h"
#include "pipeline/run_settings.h"

namespace cgsr {

struct ExportCommandOptions : RunSettings {
  std::string model;              // backbone name, spec YAML or model file
  int scale = 0;                  // 0: the model file's scale, or 2 for a backbone name
  ExportFormat format = ExportFormat::Onnx;
  std::string input = "320x240";  // LR input size WxH (written into a fixed-size ONNX file)
  bool dynamic_size = false;      // ONNX: symbolic batch, height and width
  CubicResize cubic_resize = CubicResize::Conv;  // ONNX: bicubic resize as conv (portable) or native Resize
  bool verify = false;            // run the file in the other runtimes and compare with our forward
  double tolerance = 1e-4;        // max abs error allowed by --verify
  std::string out;                // the file to write
  Precision precision = Precision::Fp32;  // int8: a quantized (QDQ) ONNX file, calibrated on `data`
  // The rendered frames int8 calibrates its activations on; with `verify`, frames that verify the
  // file besides the random inputs: `frames` in order, or the first test frame.
  std::string data;
  std::string frames;  // "A:B": frames A <= i < B of `data`, every split (a sequence, scene cuts included)
  CalibrationOptions calibration;
  // int8: --verify compares with the fused path's int8 run, whose convolutions keep their
  // results in float32 until they are stored, where ONNX Runtime's round each to int8.
  double int8_tolerance = 0.05;
};

config::Schema<ExportCommandOptions> export_schema();
nlohmann::ordered_json run_export(const ExportCommandOptions& options);

}  // namespace cgsr
