#pragma once
// The file formats a network is exported to (exporter.h), by name in configs and on the command line.

#include <string>
#include <vector>

#include "core/enum_names.h"

namespace cgsr {

enum class ExportFormat { Onnx, TorchScript };
template <>
struct EnumNames<ExportFormat> {
  static constexpr const char* kind = "format";
  static const std::vector<std::string>& names();  // onnx, torchscript
};

}  // namespace cgsr
