// Fuzz target for the image files of the CGSR dataset layout (render_data/frame_files): colour,
// depth, normal, normal-angle, edge, id and motion files, PNG or EXR as the layout stores them.
// The first byte picks the file kind; the rest is the file. decode_file promises never to throw,
// so any exception here is a bug, as is a crash or a sanitizer report. A decoded file must
// have the layout's shape and only finite values. Seeds: fuzz/corpus/frame_files (64x48 files
// of configs/scenes/tiny.yaml, each prefixed with its kind byte).

#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include <torch/torch.h>

#include "fuzz/fuzz_input.h"
#include "render_data/dataset_manifest.h"
#include "render_data/frame_files.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace cgsr;
  if (size < 1) return 0;
  const auto& kinds = all_file_kinds();
  const FileKind kind = kinds[data[0] % kinds.size()];
  const Resolution expected{64, 48};
  const auto path = fuzz::write_input("frame" + file_kind_extension(kind), data + 1, size - 1);
  // Normals are checked against geometry: give them a depth with geometry everywhere.
  const torch::Tensor depth = kind == FileKind::Normal ? torch::ones({1, expected.height, expected.width}) : torch::Tensor();
  const DecodedFile decoded = decode_file(kind, path, 0, expected, depth);
  if (decoded.problem == FileProblem::None) {
    const torch::Tensor& v = decoded.value;
    const bool shaped = v.defined() && v.dim() == 3 && v.size(1) == expected.height && v.size(2) == expected.width;
    const bool finite = !v.is_floating_point() || kind == FileKind::Depth || torch::isfinite(v).all().item<bool>();
    if (!shaped || !finite) std::abort();  // decode_file accepted a file it should have rejected
  } else if (decoded.message.empty()) {
    std::abort();  // a rejection must say why
  }
  return 0;
}
