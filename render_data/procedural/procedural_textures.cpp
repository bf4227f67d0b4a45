#include "render_data/procedural/procedural_textures.h"

#include <algorithm>
#include <cmath>

#include "core/config.h"
#include "core/error.h"
#include "core/text.h"
#include "render_data/vec_math.h"

namespace cgsr {
namespace {

uint64_t mix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}
// Uniform in [0,1) from integer coordinates and a seed.
float hash01(int64_t a, int64_t b, uint64_t seed) {
  return static_cast<float>(mix64(seed ^ mix64(static_cast<uint64_t>(a) * 0x100000001B3ULL + static_cast<uint64_t>(b))) >>
                            40) /
         static_cast<float>(1ULL << 24);
}
int positive_mod(int a, int n) { return ((a % n) + n) % n; }
float smooth(float t) { return t * t * (3 - 2 * t); }

class Canvas {
 public:
  Canvas(int size, int channels) : size_(size), channels_(channels), data_(static_cast<size_t>(size) * size * channels) {}
  void set(int x, int y, Vec3 srgb, float alpha = 1.0f) {
    uint8_t* p = &data_[(static_cast<size_t>(y) * size_ + x) * channels_];
    p[0] = byte(srgb.x);
    p[1] = byte(srgb.y);
    p[2] = byte(srgb.z);
    if (channels_ == 4) p[3] = byte(alpha);
  }
  Texture finish(const std::string& name) {
    Texture t;
    t.name = name;
    t.width = t.height = size_;
    t.channels = channels_;
    t.data = std::move(data_);
    return t;
  }

 private:
  static uint8_t byte(float v) { return static_cast<uint8_t>(std::clamp(std::lround(v * 255.0f), 0L, 255L)); }
  int size_, channels_;
  std::vector<uint8_t> data_;
};

Vec3 clamp01(Vec3 c) { return {std::clamp(c.x, 0.0f, 1.0f), std::clamp(c.y, 0.0f, 1.0f), std::clamp(c.z, 0.0f, 1.0f)}; }

}  // namespace

const std::vector<std::string>& texture_kind_names() {
  static const std::vector<std::string> names = {"bricks", "tiles",      "checker", "noise", "planks",
                                                 "glyphs", "chain_link", "plates",  "stripes",
                                                 "grate",  "grid",       "tread",   "hexes"};
  return names;
}

TextureKind texture_kind_from_name(const std::string& name) {
  const auto& names = texture_kind_names();
  for (size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<TextureKind>(i);
  throw Error("texture", "unknown texture kind '" + name + "'" + did_you_mean(name, names) + "; valid: " + join(names));
}

float tileable_noise(float x, float y, int period, int octaves, uint64_t seed) {
  float sum = 0, norm = 0, amplitude = 1;
  int lattice = 4;  // lattice points across one period at the first octave
  for (int o = 0; o < octaves; ++o, lattice *= 2, amplitude *= 0.5f) {
    const float cx = x / period * lattice, cy = y / period * lattice;
    const int ix = static_cast<int>(std::floor(cx)), iy = static_cast<int>(std::floor(cy));
    const float fx = smooth(cx - ix), fy = smooth(cy - iy);
    const uint64_t s = seed + 977 * static_cast<uint64_t>(o);
    auto v = [&](int a, int b) { return hash01(positive_mod(a, lattice), positive_mod(b, lattice), s); };
    const float top = v(ix, iy) + (v(ix + 1, iy) - v(ix, iy)) * fx;
    const float bottom = v(ix, iy + 1) + (v(ix + 1, iy + 1) - v(ix, iy + 1)) * fx;
    sum += amplitude * (top + (bottom - top) * fy);
    norm += amplitude;
  }
  return sum / norm;
}

bool texture_kind_has_holes(TextureKind kind) { return kind == TextureKind::ChainLink || kind == TextureKind::Grate; }

Texture make_texture(TextureKind kind, int size, uint64_t seed, Vec3 base, Vec3 accent) {
  if (size < 16) throw Error("texture", "size " + config::out_of_range(size, 16, config::kUnbounded));
  const int N = size;
  const bool rgba = texture_kind_has_holes(kind);
  Canvas canvas(N, rgba ? 4 : 3);
  auto noise = [&](int x, int y, int octaves = 4) { return tileable_noise(x + 0.5f, y + 0.5f, N, octaves, seed); };
  const int line = std::max(1, N / 64);  // joint / seam width in texels

  switch (kind) {
    case TextureKind::Bricks: {
      const int bh = N / 8, bw = N / 4;
      for (int y = 0; y < N; ++y)
        for (int x = 0; x < N; ++x) {
          const int row = y / bh, shifted = positive_mod(x + (row % 2) * bw / 2, N);
          const int col = shifted / bw;
          const bool mortar = (y % bh) < line || (shifted % bw) < line;
          const float n = noise(x, y);
          Vec3 c = mortar ? accent * (0.8f + 0.3f * n)
                          : base * (0.75f + 0.4f * hash01(row, col, seed)) * (0.85f + 0.3f * n);
          canvas.set(x, y, clamp01(c));
        }
      break;
    }
    case TextureKind::Tiles: {
      const int t = N / 4;
      for (int y = 0; y < N; ++y)
        for (int x = 0; x < N; ++x) {
          const bool grout = (x % t) < line || (y % t) < line;
          const bool alt = ((x / t) + (y / t)) % 2;
          const float n = noise(x, y, 3);
          const Vec3 c = grout ? accent * 0.6f : (alt ? base : base * 0.78f) * (0.92f + 0.16f * n);
          canvas.set(x, y, clamp01(c));
        }
      break;
    }
    case TextureKind::Checker: {
      const int t = N / 8;
      for (int y = 0; y < N; ++y)
        for (int x = 0; x < N; ++x) canvas.set(x, y, ((x / t) + (y / t)) % 2 ? base : accent);
      break;
    }
    case TextureKind::Noise: {
      for (int y = 0; y < N; ++y)
        for (int x = 0; x < N; ++x) {
          const float n = noise(x, y, 6);
          canvas.set(x, y, clamp01(lerp(accent, base, std::clamp((n - 0.25f) * 2.0f, 0.0f, 1.0f))));
        }
      break;
    }
    case TextureKind::Planks: {
      const int pw = N / 4;
      for (int y = 0; y < N; ++y)
        for (int x = 0; x < N; ++x) {
          const int plank = x / pw;
          const int joint = static_cast<int>(hash01(plank, 7, seed) * N);
          const bool seam = (x % pw) < line || positive_mod(y - joint, N) < line;
          // Grain: stripes along y, bent by noise; an integer number of periods across N.
          const float grain = 0.5f + 0.5f * std::sin(kTwoPiF * (x * 12.0f / N + 0.6f * noise(x, y, 3)));
          const float shade = 0.8f + 0.35f * hash01(plank, positive_mod(y - joint, N) < N / 2, seed + 1);
          const Vec3 c = seam ? accent * 0.5f : lerp(base, accent, 0.35f * grain) * shade;
          canvas.set(x, y, clamp01(c));
        }
      break;
    }
    case TextureKind::Glyphs: {
      // One glyph per 8 x 8 cell block (5 x 7 bits plus spacing), one texel per bit per 128 texels.
      const int bit = std::max(1, N / 128), cell = 8 * bit;
      const int cols = N / cell, rows = N / cell;
      for (int y = 0; y < N; ++y)
        for (int x = 0; x < N; ++x) {
          const int cx = x / cell, cy = y / cell;
          const int bx = (x % cell) / bit, by = (y % cell) / bit;
          const bool text_row = cy < rows && hash01(cy, 11, seed) < 0.75f;  // some lines are blank
          const bool space = hash01(cx, cy, seed + 3) < 0.15f;              // word gaps
          bool on = false;
          if (text_row && !space && cx < cols && bx >= 1 && bx <= 5 && by >= 1 && by <= 7) {
            // Glyph = 5 x 7 random bits with a vertical stroke bias, from a 40-glyph alphabet.
            const int glyph = static_cast<int>(hash01(cx, cy, seed + 5) * 40);
            const float p = (bx == 1 || bx == 5) ? 0.6f : 0.35f;
            on = hash01(glyph * 64 + bx, by, seed + 9) < p;
          }
          const float n = noise(x, y, 2);
          canvas.set(x, y, clamp01(on ? base : accent * (0.8f + 0.3f * n)));
        }
      break;
    }
    case TextureKind::ChainLink: {
      const int period = N / 8;
      const float wire = std::max(1.0f, N / 96.0f);
      for (int y = 0; y < N; ++y)
        for (int x = 0; x < N; ++x) {
          const int d1 = positive_mod(x + y, period), d2 = positive_mod(x - y, period);
          const float dist = std::min({static_cast<float>(d1), static_cast<float>(period - d1), static_cast<float>(d2),
                                       static_cast<float>(period - d2)});
          const bool on = dist < wire;
          const float n = noise(x, y, 2);
          canvas.set(x, y, clamp01(base * (0.8f + 0.4f * n)), on ? 1.0f : 0.0f);
        }
      break;
    }
    case TextureKind::Plates: {
      const int p = N / 2, r = std::max(1, N / 48), inset = N / 16;
      for (int y = 0; y < N; ++y)
        for (int x = 0; x < N; ++x) {
          const int px = x % p, py = y % p;
          const bool seam = px < line || py < line;
          bool rivet = false;
          for (int cx : {inset, p - inset})
            for (int cy : {inset, p - inset})
              rivet |= (px - cx) * (px - cx) + (py - cy) * (py - cy) <= r * r;
          const float brushed = tileable_noise(x + 0.5f, 0.5f + y * 0.0f, N, 5, seed + static_cast<uint64_t>(y / 2));
          const Vec3 c = seam ? accent * 0.4f : rivet ? base * 1.25f : base * (0.85f + 0.25f * brushed);
          canvas.set(x, y, clamp01(c));
        }
      break;
    }
    case TextureKind::Stripes: {
      const int w = N / 8;
      for (int y = 0; y < N; ++y)
        for (int x = 0; x < N; ++x) {
          const float n = noise(x, y, 3);
          canvas.set(x, y, clamp01((positive_mod(x + y, N) / w) % 2 ? base * (0.9f + 0.2f * n) : accent * (0.9f + 0.2f * n)));
        }
      break;
    }
    case TextureKind::Grate: {
      // 8 x 8 square holes per tile; bars a quarter of the pitch wide, slightly rusty.
      const int pitch = N / 8, bar = std::max(1, pitch / 4);
      for (int y = 0; y < N; ++y)
        for (int x = 0; x < N; ++x) {
          const bool on = (x % pitch) < bar || (y % pitch) < bar;
          const float n = noise(x, y, 3);
          canvas.set(x, y, clamp01(lerp(base, accent, 0.6f * n)), on ? 1.0f : 0.0f);
        }
      break;
    }
    case TextureKind::Grid: {
      const int pitch = std::max(2, N / 16);
      for (int y = 0; y < N; ++y)
        for (int x = 0; x < N; ++x) {
          const bool on = (x % pitch) < line || (y % pitch) < line;
          const float n = noise(x, y, 2);
          canvas.set(x, y, clamp01(on ? accent : base * (0.9f + 0.2f * n)));
        }
      break;
    }
    case TextureKind::Tread: {
      // Raised diamonds in alternating orientation, 8 per row, lit from the top left.
      const int pitch = N / 8;
      for (int y = 0; y < N; ++y)
        for (int x = 0; x < N; ++x) {
          const int cx = x / pitch, cy = y / pitch;
          const float u = (x % pitch + 0.5f) / pitch - 0.5f, v = (y % pitch + 0.5f) / pitch - 0.5f;
          // A thin diamond along one diagonal (the other in alternate cells).
          const float a = (cx + cy) % 2 ? u + v : u - v, b = (cx + cy) % 2 ? u - v : u + v;
          const bool raised = std::abs(a) < 0.32f && std::abs(b) < 0.08f;
          const float light = raised ? (b > 0 ? 1.3f : 0.75f) : 1.0f;
          const float n = tileable_noise(x + 0.5f, y + 0.5f, N, 5, seed);
          canvas.set(x, y, clamp01(lerp(base, accent, 0.25f * n) * light));
        }
      break;
    }
    case TextureKind::Hexes: {
      // Pointy hexagons on a lattice that tiles the texture: 4 columns, 4 double rows.
      const float w = static_cast<float>(N) / 4, h = static_cast<float>(N) / 4;  // cell pitch x, double-row pitch y
      const float r = w / std::sqrt(3.0f);
      for (int y = 0; y < N; ++y)
        for (int x = 0; x < N; ++x) {
          // Nearest hexagon centre among the candidates of both row offsets (periodic in N).
          float best = 1e9f, second = 1e9f;
          int id = 0;
          for (int row = -1; row <= 8; ++row)
            for (int col = -1; col <= 4; ++col) {
              const float cx = (col + 0.5f * (row % 2 != 0)) * w, cy = row * h / 2;
              const float d = std::hypot(x + 0.5f - cx, y + 0.5f - cy);
              if (d < best) second = best, best = d, id = positive_mod(col, 4) * 16 + positive_mod(row, 8);
              else if (d < second) second = d;
            }
          const bool grout = second - best < std::max(1.0f, r * 0.08f);
          const float shade = 0.8f + 0.35f * hash01(id, 3, seed);
          canvas.set(x, y, clamp01(grout ? accent * 0.6f : base * shade));
        }
      break;
    }
  }
  return canvas.finish(texture_kind_names()[static_cast<size_t>(kind)]);
}

}  // namespace cgsr
