#include "export/raw_tensor.h"

#include <torch/torch.h>

#include <cstring>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/tensor_checks.h"

namespace cgsr {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "raw tensor files are little-endian");

void write_raw_float32(const std::filesystem::path& path, const torch::Tensor& tensor) {
  const auto t = tensor.detach().to(torch::kCPU, torch::kFloat).contiguous();
  write_file_atomic(path, std::string(reinterpret_cast<const char*>(t.data_ptr<float>()),
                                      static_cast<size_t>(t.numel()) * sizeof(float)));
}

namespace {
torch::Tensor read_raw(const std::filesystem::path& path, const std::vector<int64_t>& shape, torch::ScalarType type,
                       const char* type_name) {
  const std::string bytes = read_file(path);
  auto t = torch::empty(shape, type);
  const size_t want = static_cast<size_t>(t.numel()) * t.element_size();
  if (bytes.size() != want)
    throw Error(path.string(), "holds " + std::to_string(bytes.size()) + " bytes, a " + type_name + " " +
                                   shape_string(t) + " tensor needs " + std::to_string(want));
  std::memcpy(t.data_ptr(), bytes.data(), want);
  return t;
}
}  // namespace

torch::Tensor read_raw_float32(const std::filesystem::path& path, const std::vector<int64_t>& shape) {
  return read_raw(path, shape, torch::kFloat, "float32");
}

torch::Tensor read_raw_int64(const std::filesystem::path& path, const std::vector<int64_t>& shape) {
  return read_raw(path, shape, torch::kLong, "int64");
}

}  // namespace cgsr
