// Fuzz target for model files (models/model_file): header, metadata JSON, spec, weights, in both
// format versions (raw float32 weights in version 2, a torch::save archive in version 1). The
// target rewrites the trailing checksum to match the mutated bytes (with the basis of the version
// the bytes declare), so inputs get past the corruption check into the parser behind it. Every
// input must load or be rejected with cgsr::Error; a loaded network must hold only finite weights.
// Seeds: fuzz/corpus/model_file (a version 2 file from make_seeds.sh and the version 1 test fixture).

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include <torch/torch.h>

#include "core/error.h"
#include "fuzz/fuzz_input.h"
#include "models/model_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace cgsr;
  std::string file(reinterpret_cast<const char*>(data), size);
  constexpr size_t kChecksum = 8;
  if (file.size() >= kChecksum) {
    uint64_t sum = model_file_checksum(std::string_view(file).substr(0, file.size() - kChecksum));
    for (size_t i = 0; i < kChecksum; ++i, sum >>= 8) file[file.size() - kChecksum + i] = static_cast<char>(sum & 0xff);
  }
  const auto path = fuzz::write_input("model.cgsr", reinterpret_cast<const uint8_t*>(file.data()), file.size());
  try {
    const Model model = load_model(path);
    for (const auto& p : model.network->parameters())
      if (!torch::isfinite(p).all().item<bool>()) std::abort();  // load_model accepted non-finite weights
  } catch (const Error&) {
  }
  return 0;
}
