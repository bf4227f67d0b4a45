#include "render_data/procedural/procedural_variety.h"

#include <algorithm>
#include <cmath>

#include "render_data/procedural/procedural_rng.h"
#include "render_data/procedural/procedural_textures.h"

namespace cgsr {
namespace {

int scaled(int count, float factor) { return static_cast<int>(std::lround(count * factor)); }

}  // namespace

config::Schema<ProceduralVariety> variety_schema() {
  config::Schema<ProceduralVariety> s;
  s.field("layouts", &ProceduralVariety::layouts, "layouts that layout: random draws from")
      .check([](const std::vector<ProceduralLayout>& v) { return !v.empty(); }, "needs at least one layout")
      .check(
          [](const std::vector<ProceduralLayout>& v) {
            return std::find(v.begin(), v.end(), ProceduralLayout::Random) == v.end();
          },
          "random draws from this list; name layouts (room, corridors, hall, arena, outdoor)");
  s.field("size", &ProceduralVariety::size, "grid cells per side, [lo, hi]")
      .range(5, 60)
      .check(is_range<int>, kRangeMessage);
  s.field("materials", &ProceduralVariety::materials, "texture families of walls, floors, ceilings and props")
      .one_of(texture_kind_names())
      .check(
          [](const std::vector<std::string>& v) {
            return std::any_of(v.begin(), v.end(),
                               [](const std::string& k) { return !texture_kind_has_holes(texture_kind_from_name(k)); });
          },
          "needs at least one family without holes (grate and chain_link are for thin props only)");
  s.field("pattern_scale", &ProceduralVariety::pattern_scale, "texel density multiplier, [lo, hi]")
      .range(0.1, 10)
      .check(is_range<float>, kRangeMessage);
  s.field("brightness", &ProceduralVariety::brightness, "multiplier of every light and the ambient, [lo, hi]")
      .range(0.05, 20)
      .check(is_range<float>, kRangeMessage);
  s.field("lights", &ProceduralVariety::lights, "point lights, [lo, hi]").range(0, 64).check(is_range<int>, kRangeMessage);
  s.field("coloured_lights", &ProceduralVariety::coloured_lights, "chance that a lamp has a saturated colour").range(0, 1);
  s.field("fog", &ProceduralVariety::fog, "chance of distance fog").range(0, 1);
  s.field("fog_density", &ProceduralVariety::fog_density, "fog density per metre, [lo, hi]")
      .range(0, 1)
      .check(is_range<float>, kRangeMessage);
  s.field("props", &ProceduralVariety::props, "multiplier of the solid props' counts, [lo, hi]")
      .range(0, 10)
      .check(is_range<float>, kRangeMessage);
  s.field("thin", &ProceduralVariety::thin, "multiplier of fences, railings, wires and grates, [lo, hi]")
      .range(0, 10)
      .check(is_range<float>, kRangeMessage);
  return s;
}

Vec3 hsv_colour(float hue, float saturation, float value) {
  const float h = (hue - std::floor(hue)) * 6.0f;
  auto channel = [&](float offset) {
    const float k = std::fmod(offset + h, 6.0f);
    return value - value * saturation * std::clamp(std::min(k, 4.0f - k), 0.0f, 1.0f);
  };
  return {channel(5), channel(3), channel(1)};
}

void random_albedo(ProceduralRng& rng, Vec3& base, Vec3& accent) {
  const float hue = rng.range(0, 1);
  const float saturation = rng.chance(0.3) ? rng.range(0.45f, 0.85f) : rng.range(0.05f, 0.35f);
  const float value = rng.range(0.3f, 0.85f);
  base = hsv_colour(hue, saturation, value);
  // The accent: darker joints and grout, or light markings on a dark base, sometimes another hue.
  const float accent_hue = rng.chance(0.3) ? hue + rng.range(0.3f, 0.7f) : hue;
  const float accent_value = value > 0.55f ? rng.range(0.08f, 0.35f) : rng.range(0.65f, 0.95f);
  accent = hsv_colour(accent_hue, saturation * rng.range(0.3f, 1.0f), accent_value);
}

ProceduralOptions draw_variety(const ProceduralOptions& options, uint64_t seed) {
  if (!options.variety.enabled) return options;
  const ProceduralVariety& v = options.variety;
  ProceduralRng rng(seed ^ 0x7661726965747921ULL);  // a stream of its own ("variety!")
  ProceduralOptions o = options;
  if (o.layout == ProceduralLayout::Random) o.layout = rng.pick(v.layouts);
  o.size = {rng.between(v.size[0], v.size[1]), rng.between(v.size[0], v.size[1])};
  if (o.layout == ProceduralLayout::Room) o.height = rng.range(3.2f, 5.0f);
  else if (o.layout == ProceduralLayout::Corridors) o.height = rng.range(2.8f, 4.0f);
  else if (o.layout == ProceduralLayout::Hall) o.height = rng.range(7.0f, 11.0f);
  o.height = std::max(o.height, o.camera.eye_height + 0.9f);
  o.texel_density *= rng.range(v.pattern_scale[0], v.pattern_scale[1]);

  const float solid = rng.range(v.props[0], v.props[1]), thin = rng.range(v.thin[0], v.thin[1]);
  auto& p = o.props;
  for (int* count : {&p.crates, &p.pillars, &p.spheres, &p.tori, &p.stairs, &p.signs}) *count = scaled(*count, solid);
  for (int* count : {&p.fences, &p.railings, &p.wires}) *count = scaled(*count, thin);
  p.grates = scaled(std::max(p.grates, rng.between(1, 3)), thin);

  auto& L = o.lighting;
  const bool open_sky = o.layout == ProceduralLayout::Arena || o.layout == ProceduralLayout::Outdoor;
  const float brightness = rng.range(v.brightness[0], v.brightness[1]);
  L.point_lights = rng.between(v.lights[0], v.lights[1]);
  L.point_intensity *= brightness;
  L.sun = open_sky;
  L.sun_intensity *= brightness;
  L.ambient *= brightness;
  if (open_sky) o.camera.far_plane = std::max(o.camera.far_plane, 1000.0f);

  // Sky moods: day, dusk, overcast, night: hue, saturation range and value range of the horizon
  // and of the zenith.
  struct Tone {
    float hue, s_lo, s_hi, v_lo, v_hi;
  };
  const Tone moods[4][2] = {{{0.58f, 0.2f, 0.4f, 0.7f, 0.9f}, {0.6f, 0.5f, 0.8f, 0.45f, 0.7f}},
                            {{0.07f, 0.4f, 0.7f, 0.7f, 0.95f}, {0.75f, 0.3f, 0.6f, 0.2f, 0.4f}},
                            {{0.6f, 0.0f, 0.1f, 0.5f, 0.75f}, {0.6f, 0.0f, 0.1f, 0.45f, 0.7f}},
                            {{0.63f, 0.3f, 0.6f, 0.05f, 0.15f}, {0.66f, 0.5f, 0.8f, 0.01f, 0.05f}}};
  const int mood = rng.below(4);
  const float hue = rng.range(-0.03f, 0.03f);
  auto tone = [&](const Tone& t) {
    const float saturation = rng.range(t.s_lo, t.s_hi);  // draws in a fixed order: one per statement
    const float value = rng.range(t.v_lo, t.v_hi);
    return hsv_colour(t.hue + hue, saturation, value);
  };
  const Vec3 horizon = tone(moods[mood][0]);
  const Vec3 zenith = tone(moods[mood][1]);
  o.sky_horizon = {horizon.x, horizon.y, horizon.z};
  o.sky_zenith = {zenith.x, zenith.y, zenith.z};
  if (rng.chance(v.fog)) {
    o.fog.density = rng.range(v.fog_density[0], v.fog_density[1]);
    o.fog.start = rng.range(0.0f, 6.0f);
    const Vec3 colour = open_sky ? horizon : tone({rng.range(0, 1), 0.0f, 0.3f, 0.1f, 0.6f});
    o.fog.color = {colour.x, colour.y, colour.z};
  }
  return o;
}

}  // namespace cgsr
