#pragma once
// Raw little-endian float32 (and int64) files: the exchange format with the out-of-process runtimes
// (ONNX Runtime in node, torch.jit.load in Python). The shape travels separately, in the job
// description, so a file is exactly numel * element size bytes.

#include <torch/types.h>

#include <cstdint>
#include <filesystem>
#include <vector>

namespace cgsr {

void write_raw_float32(const std::filesystem::path& path, const torch::Tensor& tensor);

// Throws cgsr::Error naming the file when its size is not that of `shape`.
torch::Tensor read_raw_float32(const std::filesystem::path& path, const std::vector<int64_t>& shape);
// The same for int64 (an output such as an ArgMax index).
torch::Tensor read_raw_int64(const std::filesystem::path& path, const std::vector<int64_t>& shape);

}  // namespace cgsr
