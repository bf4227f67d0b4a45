// Fuzz target for the sub-pixel BSP border file (render_data/bsp_border_file): each input is a
// frame's file of a 64x48 data set. It must load or be rejected with cgsr::Error; a file that
// loads re-encodes to the same bytes (the format has one encoding per image) and every leaf
// lookup stays inside its tree. Seeds: fuzz/corpus/bsp_border (configs/scenes/tiny.yaml rendered
// with bsp_border: {depth: 2}).

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "core/error.h"
#include "fuzz/fuzz_input.h"
#include "render_data/bsp_border_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace cgsr;
  const auto path = fuzz::write_input("dataset/64x48/bsp_border/000000.bsp", data, size);
  try {
    const BspBorderImage image = read_bsp_border_file(path, 0, {64, 48});
    if (encode_bsp_border(image) != std::string(reinterpret_cast<const char*>(data), size)) std::abort();
    for (size_t k = 0; k < image.size(); ++k) {
      const BspTree& t = image.tree(k);
      const int x = image.pixel(k) % 64, y = image.pixel(k) / 64;
      for (double dy : {0.1, 0.5, 0.9})
        for (double dx : {0.1, 0.5, 0.9}) {
          const int leaf = t.leaf_at(x + dx, y + dy);
          if (leaf < 0 || leaf >= static_cast<int>(t.leaves.size())) std::abort();
        }
    }
  } catch (const Error&) {
  }
  return 0;
}
