#pragma once
// Tileable procedural textures for the procedural scenes: every pattern is periodic in the
// texture size, so repeat wrapping shows no seams. Colours are given and stored sRGB-encoded.

#include <cstdint>
#include <string>
#include <vector>

#include "render_data/scene.h"

namespace cgsr {

enum class TextureKind {
  Bricks,     // running-bond bricks with mortar joints and per-brick colour variation
  Tiles,      // square floor tiles with grout lines, alternating shades
  Checker,    // two-colour checkerboard (8 x 8 squares)
  Noise,      // fractal value noise (concrete, plaster, rock)
  Planks,     // wooden planks: stripes with grain noise and plank ends
  Glyphs,     // rows of small glyph-like bitmap characters on a panel (signs, screens)
  ChainLink,  // RGBA diamond wire mesh with transparent holes (fences; alpha-tested)
  Plates,     // metal plates with seams and rivets
  Stripes,    // diagonal hazard stripes
  // Families added for procedural variety (kept after the first nine: their names index materials).
  Grate,      // RGBA floor/wall grate: a grid of bars with square holes (alpha-tested)
  Grid,       // fine grid lines on a plain panel (high frequency: 16 cells per tile)
  Tread,      // metal tread plate: rows of raised diamonds, high frequency
  Hexes,      // hexagonal tiles with grout lines
};

// Kinds whose texture has an alpha channel of holes (a material needs an alpha cutoff).
bool texture_kind_has_holes(TextureKind kind);

const std::vector<std::string>& texture_kind_names();
TextureKind texture_kind_from_name(const std::string& name);  // cgsr::Error listing valid names

// `size` x `size` texels (>= 16). `base` and `accent` are sRGB colours in [0,1].
Texture make_texture(TextureKind kind, int size, uint64_t seed, Vec3 base, Vec3 accent);

// Tileable fractal value noise in [0,1] at texel (x, y) of a `period`-periodic lattice.
float tileable_noise(float x, float y, int period, int octaves, uint64_t seed);

}  // namespace cgsr
