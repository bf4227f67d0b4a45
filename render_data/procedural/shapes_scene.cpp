#include "render_data/procedural/shapes_scene.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "render_data/procedural/procedural_rng.h"
#include "render_data/procedural/procedural_textures.h"
#include "render_data/vec_math.h"

namespace cgsr {
namespace {

constexpr float kBackgroundDistance = 10.0f;  // metres; the scene is scale-free, only ratios matter
constexpr float kMaxAspect = 16.0f / 9.0f;    // widest view the shapes and the background cover
constexpr int kRoundSegments = 64;            // discs and rings: a 64-gon's flats stay sub-pixel here
constexpr int kCurveSegments = 32;

// A shape in its own plane, in view heights around its centre: a triangulated outline,
// counter-clockwise seen from the camera.
struct Outline {
  std::vector<Vec2> points;
  std::vector<uint32_t> indices;

  void fan(int first_rim, int rim_count) {  // centre point first_rim - 1
    for (int k = 0; k < rim_count; ++k)
      indices.insert(indices.end(), {static_cast<uint32_t>(first_rim - 1), static_cast<uint32_t>(first_rim + k),
                                     static_cast<uint32_t>(first_rim + (k + 1) % rim_count)});
  }
  void quad(uint32_t a, uint32_t b, uint32_t c, uint32_t d) { indices.insert(indices.end(), {a, b, c, a, c, d}); }
};

Vec2 polar(float radius, float angle) { return {radius * std::cos(angle), radius * std::sin(angle)}; }

// Star-shaped polygon around the centre: `sides` corners at jittered angles and radii.
Outline jittered_polygon(ProceduralRng& rng, int sides, float radius, float angle_jitter, float min_radius) {
  Outline o;
  o.points.push_back({0, 0});
  const float start = rng.range(0, kTwoPiF), step = kTwoPiF / static_cast<float>(sides);
  for (int k = 0; k < sides; ++k) {
    const float r = radius * rng.range(min_radius, 1.0f);  // draws in statement order: same on every compiler
    o.points.push_back(polar(r, start + k * step + rng.range(-angle_jitter, angle_jitter)));
  }
  o.fan(1, sides);
  return o;
}

Outline regular_polygon(float radius, int sides, float start) {
  Outline o;
  o.points.push_back({0, 0});
  for (int k = 0; k < sides; ++k) o.points.push_back(polar(radius, start + kTwoPiF * k / static_cast<float>(sides)));
  o.fan(1, sides);
  return o;
}

Outline ring(float outer, float inner, float start) {
  Outline o;
  for (int k = 0; k < kRoundSegments; ++k) {
    const float a = start + kTwoPiF * k / static_cast<float>(kRoundSegments);
    o.points.push_back(polar(inner, a));
    o.points.push_back(polar(outer, a));
  }
  for (uint32_t k = 0; k < kRoundSegments; ++k) {
    const uint32_t next = (k + 1) % kRoundSegments;
    o.quad(2 * k, 2 * k + 1, 2 * next + 1, 2 * next);
  }
  return o;
}

// A stroke of width `width` along a polyline (bars: two points; curves: a sampled Bezier).
Outline stroke(const std::vector<Vec2>& path, float width) {
  Outline o;
  for (size_t i = 0; i < path.size(); ++i) {
    const Vec2 d = path[std::min(i + 1, path.size() - 1)] - path[i == 0 ? 0 : i - 1];
    const float len = std::max(1e-12f, std::sqrt(d.x * d.x + d.y * d.y));
    const Vec2 left{-d.y / len * width * 0.5f, d.x / len * width * 0.5f};
    o.points.push_back(path[i] - left);  // right side, then left side: counter-clockwise quads
    o.points.push_back(path[i] + left);
  }
  for (uint32_t i = 0; i + 1 < path.size(); ++i) o.quad(2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1);
  return o;
}

Outline bezier_stroke(ProceduralRng& rng, float radius, float width) {
  const float a = rng.range(0, kTwoPiF);
  const Vec2 p0 = polar(radius, a), p2 = polar(radius, a + kPiF);
  const float bend = radius * rng.range(0.3f, 1.0f);
  const Vec2 p1 = polar(rng.chance(0.5) ? bend : -bend, a + kPiF / 2);
  std::vector<Vec2> path;
  for (int k = 0; k <= kCurveSegments; ++k) {
    const float t = static_cast<float>(k) / kCurveSegments;
    path.push_back(p0 * ((1 - t) * (1 - t)) + p1 * (2 * (1 - t) * t) + p2 * (t * t));
  }
  return stroke(path, width);
}

enum class ShapeKind { Triangle, Quad, Disc, Polygon, Ring, Bar, Curve };

Outline make_outline(ShapeKind kind, ProceduralRng& rng, const ShapesOptions& o) {
  const float radius = 0.5f * rng.range(o.size[0], o.size[1]);
  const float width = rng.range(o.thickness[0], o.thickness[1]);
  switch (kind) {
    case ShapeKind::Triangle: return jittered_polygon(rng, 3, radius, 0.5f, 0.6f);
    case ShapeKind::Quad: return jittered_polygon(rng, 4, radius, 0.35f, 0.6f);
    case ShapeKind::Disc: return regular_polygon(radius, kRoundSegments, 0);
    case ShapeKind::Polygon: {
      const int sides = rng.between(3, 8);
      return regular_polygon(radius, sides, rng.range(0, kTwoPiF));
    }
    case ShapeKind::Ring: return ring(radius, radius - std::min(width, 0.7f * radius), rng.range(0, kTwoPiF));
    case ShapeKind::Bar: {
      const float a = rng.range(0, kTwoPiF);
      return stroke({polar(radius, a), polar(radius, a + kPiF)}, width);
    }
    case ShapeKind::Curve: return bezier_stroke(rng, radius, width);
  }
  return {};
}

// Linear colours drawn so their sRGB encodings spread over the whole range (squared ~ decoded).
Vec3 random_color(ProceduralRng& rng) {
  const float r = rng.range(0, 1), g = rng.range(0, 1), b = rng.range(0, 1);
  return {r * r, g * g, b * b};
}

class ShapesBuilder {
 public:
  ShapesBuilder(const ShapesOptions& o, uint64_t seed) : o_(o), rng_(seed) {
    view_height_ = 2 * kBackgroundDistance * std::tan(o.camera.vfov * kPiF / 360.0f);
    for (const auto& name : texture_kind_names())
      if (!texture_kind_has_holes(texture_kind_from_name(name))) texture_kinds_.push_back(texture_kind_from_name(name));
  }

  SceneBundle build() {
    scene_.name = o_.name;
    // The background: wide enough for any allowed drift, dolly and roll.
    const float half = 2.0f * (kMaxAspect / 2 + o_.camera.drift + 1.0f);
    Outline plane;
    plane.points = {{-half, -half}, {half, -half}, {half, half}, {-half, half}};
    plane.quad(0, 1, 2, 3);
    add_object("background", plane, {0, 0}, kBackgroundDistance);
    scene_.sky.horizon = scene_.sky.zenith = random_color(rng_);  // never seen; a plain colour if it were

    std::vector<ShapeKind> kinds;
    const std::pair<ShapeKind, int> counts[] = {
        {ShapeKind::Triangle, o_.counts.triangles}, {ShapeKind::Quad, o_.counts.quads},
        {ShapeKind::Disc, o_.counts.discs},         {ShapeKind::Polygon, o_.counts.polygons},
        {ShapeKind::Ring, o_.counts.rings},         {ShapeKind::Bar, o_.counts.bars},
        {ShapeKind::Curve, o_.counts.curves}};
    for (const auto& [kind, count] : counts) kinds.insert(kinds.end(), count, kind);
    // Distinct depth layers in a random order: layer k of n at (1 - depth_range (k + 1) / n) x D.
    std::vector<int> layer(kinds.size());
    std::iota(layer.begin(), layer.end(), 0);
    for (size_t i = layer.size(); i > 1; --i) std::swap(layer[i - 1], layer[rng_.below(static_cast<int>(i))]);
    const float reach_x = kMaxAspect / 2 + o_.camera.drift / 2, reach_y = 0.5f + o_.camera.drift / 2;
    static const char* const kNames[] = {"triangle", "quad", "disc", "polygon", "ring", "bar", "curve"};
    for (size_t i = 0; i < kinds.size(); ++i) {
      const Outline outline = make_outline(kinds[i], rng_, o_);
      const Vec2 centre{rng_.range(-reach_x, reach_x), rng_.range(-reach_y, reach_y)};
      const float depth = kBackgroundDistance *
                          (1 - o_.depth_range * static_cast<float>(layer[i] + 1) / static_cast<float>(kinds.size()));
      add_object(std::string(kNames[static_cast<int>(kinds[i])]) + std::to_string(i), outline, centre, depth);
    }

    SceneBundle bundle;
    bundle.scene = std::move(scene_);
    bundle.camera = camera_path();
    return bundle;
  }

 private:
  // One object (its own material and id): the outline placed at `centre` (view heights, as
  // seen from the origin) at `depth` metres, scaled with depth so its on-screen size is the
  // drawn one whatever the layer.
  void add_object(const std::string& name, const Outline& outline, Vec2 centre, float depth) {
    const float scale = view_height_ * depth / kBackgroundDistance;
    Material material;
    material.name = name;
    material.unlit = true;
    Mesh mesh;
    mesh.name = name;
    mesh.object_id = static_cast<int>(scene_.meshes.size());
    mesh.material = static_cast<int>(scene_.materials.size());
    const bool gradient = rng_.chance(o_.gradients), textured = rng_.chance(o_.textured);
    const Vec3 from = random_color(rng_), to = random_color(rng_);
    const Vec2 direction = polar(1, rng_.range(0, kTwoPiF));
    float extent = 0;  // the outline's radius: gradients and textures span the shape
    for (const Vec2& p : outline.points) extent = std::max(extent, std::sqrt(p.x * p.x + p.y * p.y));
    extent = std::max(extent, 1e-6f);
    const float uv_repeats = rng_.range(1.0f, 3.0f);
    material.tint = gradient || textured ? Vec3{1, 1, 1} : from;
    if (textured) {
      material.albedo_texture = static_cast<int>(scene_.textures.size());
      const TextureKind kind = rng_.pick(texture_kinds_);
      const uint64_t texture_seed = rng_.bits();
      const Vec3 base{rng_.range(0, 1), rng_.range(0, 1), rng_.range(0, 1)};  // sRGB
      const Vec3 accent{rng_.range(0, 1), rng_.range(0, 1), rng_.range(0, 1)};
      scene_.textures.push_back(make_texture(kind, o_.texture_size, texture_seed, base, accent));
    }
    for (const Vec2& p : outline.points) {
      const Vec2 world = (centre + p) * scale;
      mesh.positions.push_back({world.x, world.y, -depth});
      mesh.normals.push_back({0, 0, 1});
      mesh.uvs.push_back({0.5f + 0.5f * uv_repeats * p.x / extent, 0.5f - 0.5f * uv_repeats * p.y / extent});
      if (gradient) {
        const float t = std::clamp(0.5f + 0.5f * (p.x * direction.x + p.y * direction.y) / extent, 0.0f, 1.0f);
        mesh.colors.push_back(lerp(from, to, t));
      }
    }
    mesh.indices = outline.indices;
    scene_.materials.push_back(std::move(material));
    scene_.meshes.push_back(std::move(mesh));
  }

  // A smooth path through `keys` random poses: positions in a disc of diameter `drift` view
  // heights (plus a little dolly), roll either way; always looking straight at the background.
  CameraPath camera_path() {
    CameraPath path;
    path.near_plane = 0.25f;
    path.far_plane = 2 * kBackgroundDistance;
    for (int k = 0; k < o_.camera.keys; ++k) {
      const float r = 0.5f * o_.camera.drift * std::sqrt(rng_.range(0, 1)) * view_height_;
      const Vec2 p = polar(r, rng_.range(0, kTwoPiF));
      CameraKey key;
      key.time = k;
      key.pose.position = {p.x, p.y, kBackgroundDistance * rng_.range(-o_.camera.dolly, o_.camera.dolly)};
      key.pose.roll = rng_.range(-o_.camera.roll, o_.camera.roll);
      key.pose.vfov = o_.camera.vfov;
      path.keys.push_back(key);
    }
    return path;
  }

  const ShapesOptions& o_;
  ProceduralRng rng_;
  float view_height_ = 1;  // metres at the background distance
  std::vector<TextureKind> texture_kinds_;  // the kinds without holes
  Scene scene_;
};

config::Schema<ShapeCounts> counts_schema() {
  config::Schema<ShapeCounts> s;
  s.field("triangles", &ShapeCounts::triangles, "random triangles").range(0, 10000);
  s.field("quads", &ShapeCounts::quads, "random quadrilaterals").range(0, 10000);
  s.field("discs", &ShapeCounts::discs, "circles").range(0, 10000);
  s.field("polygons", &ShapeCounts::polygons, "regular polygons of 3 to 8 sides").range(0, 10000);
  s.field("rings", &ShapeCounts::rings, "annuli").range(0, 10000);
  s.field("bars", &ShapeCounts::bars, "thin straight bars").range(0, 10000);
  s.field("curves", &ShapeCounts::curves, "thin quadratic Bezier strokes").range(0, 10000);
  return s;
}

config::Schema<ShapesCamera> shapes_camera_schema() {
  config::Schema<ShapesCamera> s;
  s.field("vfov", &ShapesCamera::vfov, "vertical field of view, degrees").range(10, 120);
  s.field("drift", &ShapesCamera::drift, "how far the camera wanders, fraction of the view height").range(0, 2);
  s.field("dolly", &ShapesCamera::dolly, "forward/back wandering, fraction of the background distance").range(0, 0.3);
  s.field("roll", &ShapesCamera::roll, "roll either way, degrees").range(0, 45);
  s.field("keys", &ShapesCamera::keys, "random poses the path passes through").range(2, 1000);
  return s;
}

}  // namespace

config::Schema<ShapesOptions> shapes_schema() {
  config::Schema<ShapesOptions> s;
  s.field("name", &ShapesOptions::name, "scene name");
  s.field("variant", &ShapesOptions::variant, "0: the scene of the render seed; N: another scene of the same seed")
      .range(0, 1000000000);
  s.section("counts", &ShapesOptions::counts, counts_schema(), "how many shapes of each kind");
  s.field("size", &ShapesOptions::size, "[lo, hi] shape extent, fraction of the view height")
      .range(0.001, 4)
      .check(is_range<float>, kRangeMessage);
  s.field("thickness", &ShapesOptions::thickness,
          "[lo, hi] width of bars, rings and curves, fraction of the view height")
      .range(0.0001, 1)
      .check(is_range<float>, kRangeMessage);
  s.field("depth_range", &ShapesOptions::depth_range, "depth spread of the shapes, fraction of the background distance")
      .range(0.01, 0.6);
  s.field("gradients", &ShapesOptions::gradients, "chance of a two-colour gradient per shape").range(0, 1);
  s.field("textured", &ShapesOptions::textured, "chance of a procedural texture per shape").range(0, 1);
  s.field("texture_size", &ShapesOptions::texture_size, "texels per side of each texture").range(16, 1024);
  s.section("camera", &ShapesOptions::camera, shapes_camera_schema(), "the slowly drifting camera");
  s.validate([](const ShapesOptions& o, const config::Cursor& at, const YAML::Node& node) {
    if (o.counts.total() == 0) at.child("counts").fail(node, "needs at least one shape (every count is 0)");
  });
  return s;
}

SceneBundle make_shapes_scene(const ShapesOptions& options, uint64_t seed) {
  return ShapesBuilder(options, variant_seed(seed, options.variant)).build();
}

void register_shapes_scene_source(Registry<SceneSourceFactory>& registry) {
  registry.add(
      "shapes",
      [](const config::Block& block, uint64_t seed) {
        return make_shapes_scene(config::parse_block_options(block, shapes_schema()), seed);
      },
      "random flat shapes (triangles, quads, discs, polygons, rings, bars, curves) over a background plane, "
      "a slowly drifting camera; aliased edge training data (SRPO)");
}

}  // namespace cgsr
