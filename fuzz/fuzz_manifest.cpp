// Fuzz target for the dataset manifest (render_data/dataset_manifest): each input is a
// manifest.yaml in an otherwise empty dataset folder, read on its own and then opened as a
// dataset. Every input must load or be rejected with cgsr::Error. Seeds: fuzz/corpus/manifest.

#include <cstddef>
#include <cstdint>

#include "core/error.h"
#include "fuzz/fuzz_input.h"
#include "render_data/dataset.h"
#include "render_data/dataset_manifest.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace cgsr;
  const auto root = fuzz::write_input("dataset/manifest.yaml", data, size).parent_path();
  try {
    const DatasetManifest manifest = read_manifest(root);
    for (size_t r = 0; r < manifest.resolutions.size(); ++r) (void)manifest.file(root, 0, r, FileKind::Color);
  } catch (const Error&) {
  }
  try {
    const Dataset dataset = Dataset::open(root);
    (void)dataset.frames(Split::Test);
  } catch (const Error&) {
  }
  return 0;
}
