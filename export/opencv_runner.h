#pragma once
// Running an exported ONNX file in OpenCV DNN (readNetFromONNX, CPU backend).
//
// OpenCV 4.6 imports DepthToSpace (and so every pixel-shuffle model) only at the fixed size
// written in the file, so only fixed-size exports run here: a dynamic-size file is refused
// with an explanation, and inputs must have exactly the declared shapes.

#include <filesystem>
#include <string>

#include "export/export_signature.h"

namespace cgsr {

// Empty when the file can run in OpenCV DNN, else why not (a dynamic-size export).
std::string opencv_dnn_unsupported_reason(const std::filesystem::path& onnx_file);

// Outputs by name ("sr"). Throws cgsr::Error naming the file for a dynamic export, inputs that
// do not match the declared shapes, or an OpenCV import/run failure (with OpenCV's message).
NamedTensors run_opencv_dnn(const std::filesystem::path& onnx_file, const NamedTensors& inputs);

std::string opencv_version();

}  // namespace cgsr
