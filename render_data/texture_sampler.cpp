#include "render_data/texture_sampler.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace cgsr {
namespace {

float srgb_to_linear_value(float s) {
  return s <= 0.04045f ? s / 12.92f : std::pow((s + 0.055f) / 1.055f, 2.4f);
}
float linear_to_srgb_value(float l) {
  l = std::clamp(l, 0.0f, 1.0f);
  return l <= 0.0031308f ? 12.92f * l : 1.055f * std::pow(l, 1.0f / 2.4f) - 0.055f;
}
const std::array<float, 256>& srgb_table() {
  static const std::array<float, 256> t = [] {
    std::array<float, 256> a{};
    for (int i = 0; i < 256; ++i) a[i] = srgb_to_linear_value(i / 255.0f);
    return a;
  }();
  return t;
}
uint8_t to_byte(float v) { return static_cast<uint8_t>(std::clamp(std::lround(v * 255.0f), 0L, 255L)); }

int wrap(int i, int n) {
  const int r = i % n;
  return r < 0 ? r + n : r;
}

}  // namespace

MipChain::MipChain(const Texture& texture) : srgb_(texture.srgb) {
  Level base;
  base.width = texture.width;
  base.height = texture.height;
  base.rgba.resize(static_cast<size_t>(base.width) * base.height * 4);
  for (size_t i = 0, n = static_cast<size_t>(base.width) * base.height; i < n; ++i) {
    for (int c = 0; c < 3; ++c) base.rgba[i * 4 + c] = texture.data[i * texture.channels + c];
    base.rgba[i * 4 + 3] = texture.channels == 4 ? texture.data[i * 4 + 3] : 255;
  }
  levels_.push_back(std::move(base));
  while (levels_.back().width > 1 || levels_.back().height > 1) {
    const Level& src = levels_.back();
    Level dst;
    dst.width = std::max(1, src.width / 2);
    dst.height = std::max(1, src.height / 2);
    dst.rgba.resize(static_cast<size_t>(dst.width) * dst.height * 4);
    for (int r = 0; r < dst.height; ++r)
      for (int c = 0; c < dst.width; ++c) {
        // Source block: 2x2, widened to 3 at the last row/column of an odd-sized level.
        const int r0 = r * 2, r1 = (r == dst.height - 1) ? src.height : std::min(src.height, r0 + 2);
        const int c0 = c * 2, c1 = (c == dst.width - 1) ? src.width : std::min(src.width, c0 + 2);
        float sum[4] = {0, 0, 0, 0};
        for (int y = r0; y < r1; ++y)
          for (int x = c0; x < c1; ++x) {
            const LinearRgba t = decode(&src.rgba[(static_cast<size_t>(y) * src.width + x) * 4]);
            sum[0] += t.r;
            sum[1] += t.g;
            sum[2] += t.b;
            sum[3] += t.a;
          }
        const float inv = 1.0f / static_cast<float>((r1 - r0) * (c1 - c0));
        uint8_t* out = &dst.rgba[(static_cast<size_t>(r) * dst.width + c) * 4];
        for (int k = 0; k < 3; ++k) out[k] = to_byte(srgb_ ? linear_to_srgb_value(sum[k] * inv) : sum[k] * inv);
        out[3] = to_byte(sum[3] * inv);
      }
    levels_.push_back(std::move(dst));
  }
}

LinearRgba MipChain::decode(const uint8_t* p) const {
  if (srgb_) {
    const auto& t = srgb_table();
    return {t[p[0]], t[p[1]], t[p[2]], p[3] / 255.0f};
  }
  return {p[0] / 255.0f, p[1] / 255.0f, p[2] / 255.0f, p[3] / 255.0f};
}

LinearRgba MipChain::texel(int level, int row, int col) const {
  const Level& l = levels_[std::clamp(level, 0, levels() - 1)];
  return decode(&l.rgba[(static_cast<size_t>(wrap(row, l.height)) * l.width + wrap(col, l.width)) * 4]);
}

LinearRgba MipChain::bilinear(const Level& level, float u, float v, bool repeat) const {
  if (!std::isfinite(u) || !std::isfinite(v)) u = v = 0.0f;
  if (repeat) u -= std::floor(u), v -= std::floor(v);  // keeps the integer conversions in range
  else u = std::clamp(u, -1.0f, 2.0f), v = std::clamp(v, -1.0f, 2.0f);
  // Texel centres sit at (c + 0.5) / width: shift by half a texel to find the four neighbours.
  const float x = u * level.width - 0.5f, y = v * level.height - 0.5f;
  const float fx = std::floor(x), fy = std::floor(y);
  const float tx = x - fx, ty = y - fy;
  int c0 = static_cast<int>(fx), r0 = static_cast<int>(fy), c1 = c0 + 1, r1 = r0 + 1;
  if (repeat) {
    c0 = wrap(c0, level.width), c1 = wrap(c1, level.width), r0 = wrap(r0, level.height), r1 = wrap(r1, level.height);
  } else {
    c0 = std::clamp(c0, 0, level.width - 1), c1 = std::clamp(c1, 0, level.width - 1);
    r0 = std::clamp(r0, 0, level.height - 1), r1 = std::clamp(r1, 0, level.height - 1);
  }
  auto at = [&](int r, int c) { return decode(&level.rgba[(static_cast<size_t>(r) * level.width + c) * 4]); };
  const LinearRgba a = at(r0, c0), b = at(r0, c1), c = at(r1, c0), d = at(r1, c1);
  const float w00 = (1 - tx) * (1 - ty), w01 = tx * (1 - ty), w10 = (1 - tx) * ty, w11 = tx * ty;
  return {a.r * w00 + b.r * w01 + c.r * w10 + d.r * w11, a.g * w00 + b.g * w01 + c.g * w10 + d.g * w11,
          a.b * w00 + b.b * w01 + c.b * w10 + d.b * w11, a.a * w00 + b.a * w01 + c.a * w10 + d.a * w11};
}

LinearRgba MipChain::sample_trilinear(Vec2 uv, Vec2 duv_dx, Vec2 duv_dy) const {
  const float w = static_cast<float>(levels_[0].width), h = static_cast<float>(levels_[0].height);
  const float lx = std::hypot(duv_dx.x * w, duv_dx.y * h), ly = std::hypot(duv_dy.x * w, duv_dy.y * h);
  const float footprint = std::max(lx, ly);
  const float lod = footprint > 1.0f ? std::log2(footprint) : 0.0f;
  const float max_lod = static_cast<float>(levels() - 1);
  if (!(lod > 0.0f)) return bilinear(levels_[0], uv.x, uv.y, true);  // also catches NaN footprints
  if (lod >= max_lod) return bilinear(levels_.back(), uv.x, uv.y, true);
  const int l0 = static_cast<int>(lod);
  const float t = lod - static_cast<float>(l0);
  const LinearRgba a = bilinear(levels_[l0], uv.x, uv.y, true), b = bilinear(levels_[l0 + 1], uv.x, uv.y, true);
  return {a.r + (b.r - a.r) * t, a.g + (b.g - a.g) * t, a.b + (b.b - a.b) * t, a.a + (b.a - a.a) * t};
}

LinearRgba MipChain::sample_bilinear_clamped(Vec2 uv) const { return bilinear(levels_[0], uv.x, uv.y, false); }

}  // namespace cgsr
