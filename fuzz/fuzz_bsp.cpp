// libFuzzer target for the Quake III BSP parser and the code that walks a parsed map: patch
// tessellation, the collision tree, and the entity string. Every input must either parse or be
// rejected with cgsr::Error; crashes, hangs and sanitizer reports are bugs.
//
//   cmake -S . -B build-fuzz -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCGSR_FUZZ=ON -DCGSR_BUILD_TESTS=OFF -DCGSR_BUILD_BENCH=OFF
//   cmake --build build-fuzz --target fuzz_bsp
//   build-fuzz/fuzz/fuzz_bsp -max_total_time=300 -max_len=65536 <corpus dir>

#include <cstddef>
#include <cstdint>

#include "core/error.h"
#include "render_data/q3/bezier_patch.h"
#include "render_data/q3/bsp_file.h"
#include "render_data/q3/bsp_trace.h"
#include "render_data/q3/entities.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace cgsr::q3;
  BspFile bsp;
  try {
    bsp = parse_bsp(data, size, "fuzz.bsp");
  } catch (const cgsr::Error&) {
    return 0;
  }
  for (const BspFace& f : bsp.faces) {
    if (f.type == FaceType::Patch) {
      const std::vector<BspVertex> control(bsp.vertices.begin() + f.first_vertex,
                                           bsp.vertices.begin() + f.first_vertex + f.vertex_count);
      tessellate_patch(control, f.patch_size[0], f.patch_size[1], 2);
    } else if (f.type != FaceType::Billboard) {
      volatile uint8_t sink = 0;
      for (int k = 0; k < f.mesh_vert_count; ++k)
        sink = sink + bsp.vertices[f.first_vertex + bsp.mesh_verts[f.first_mesh_vert + k]].color[0];
    }
  }
  const BspCollision collision(bsp);
  collision.trace({-512, -512, -64}, {512, 512, 256}, {16, 16, 8});
  collision.cluster_at({0, 0, 0});
  try {
    parse_entities(bsp.entities, "fuzz.bsp: entities");
  } catch (const cgsr::Error&) {
  }
  return 0;
}
