#pragma once
// Quake III curved surfaces: a grid of W x H control points (both odd) is a set of
// ((W-1)/2) x ((H-1)/2) biquadratic Bezier patches sharing their border rows and columns.
// Each patch is tessellated into `level` x `level` quads; neighbouring patches share the vertices
// of their common border, so a grid is watertight. The basis is evaluated symmetrically (the
// weights of t and 1-t are the same floating-point numbers), so two separate grids whose borders
// have the same control points, traversed in either direction, produce bit-identical border
// vertices: no cracks between them either.

#include <cstdint>
#include <vector>

#include "render_data/q3/bsp_file.h"

namespace cgsr::q3 {

struct PatchVertex {
  Vec3 position;
  Vec3 normal;  // the Bezier interpolation of the control normals, renormalized
  Vec2 uv;
  Vec2 lightmap_uv;
  std::array<float, 4> color{};  // vertex colour in [0,1]
};

struct TessellatedPatch {
  int columns = 0, rows = 0;           // vertex grid size: ((W-1)/2*level+1) x ((H-1)/2*level+1)
  std::vector<PatchVertex> vertices;   // row-major, rows x columns
  std::vector<uint32_t> indices;       // triangle list, two per quad, same winding as the game
};

// `control` holds W*H points in row-major order (W across). level >= 1.
TessellatedPatch tessellate_patch(const std::vector<BspVertex>& control, int width, int height, int level);

// The biquadratic surface at (u, v) in [0,1]^2 of one 3x3 patch (row-major control points).
PatchVertex evaluate_patch(const BspVertex* control3x3, float u, float v);

}  // namespace cgsr::q3
