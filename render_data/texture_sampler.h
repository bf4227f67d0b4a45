#pragma once
// Texture sampling for the rasterizer: a mip chain built from a scene Texture, trilinear
// filtering with repeat wrapping (albedo), and bilinear clamp-to-edge sampling (lightmaps).
// Texel space: texel (r, c) covers uv [c, c+1)/width x [r, r+1)/height, sampled at its centre.
// Levels keep the texture's 8-bit encoding; filtering happens on decoded linear values.

#include <cstdint>
#include <vector>

#include "render_data/scene.h"
#include "render_data/vec_math.h"

namespace cgsr {

struct LinearRgba {
  float r = 0, g = 0, b = 0, a = 1;
};

class MipChain {
 public:
  MipChain() = default;
  // Builds levels down to 1x1 by 2x2 box filtering in linear space (odd sizes: the last
  // row/column folds into the previous one).
  explicit MipChain(const Texture& texture);

  int levels() const { return static_cast<int>(levels_.size()); }
  int width(int level = 0) const { return levels_[level].width; }
  int height(int level = 0) const { return levels_[level].height; }

  // Trilinear sample at `uv` with screen-space derivatives duv/dx, duv/dy (in uv units per
  // pixel), which choose the level of detail as on a GPU: log2 of the longer footprint in texels.
  LinearRgba sample_trilinear(Vec2 uv, Vec2 duv_dx, Vec2 duv_dy) const;
  // Bilinear sample of level 0, clamped to the edge (no repeat).
  LinearRgba sample_bilinear_clamped(Vec2 uv) const;
  // Nearest texel of `level`, repeat wrapping (tests and debugging).
  LinearRgba texel(int level, int row, int col) const;

 private:
  struct Level {
    int width = 0, height = 0;
    std::vector<uint8_t> rgba;  // 4 bytes per texel in the texture's encoding
  };
  LinearRgba bilinear(const Level& level, float u, float v, bool repeat) const;
  LinearRgba decode(const uint8_t* p) const;

  std::vector<Level> levels_;
  bool srgb_ = true;
};

}  // namespace cgsr
