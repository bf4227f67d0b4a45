#include "render_data/renderer.h"

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/blocked_range2d.h>
#include <oneapi/tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <map>

#include "core/config.h"
#include "core/error.h"
#include "render_data/hr_samples.h"

namespace cgsr {
namespace {

constexpr float kHalfPi = 1.57079632679f;

float encode_srgb(float linear) {
  const float l = std::clamp(linear, 0.0f, 1.0f);
  return l <= 0.0031308f ? 12.92f * l : 1.055f * std::pow(l, 1.0f / 2.4f) - 0.055f;
}

// Everything one render() call owns: the cameras, the vertex stage output, the visibility
// buffer and the target G-buffer.
struct RenderContext {
  FrameCamera camera, previous;
  std::vector<Vec4> clip;    // per vertex, clip space of `camera`
  std::vector<float> depth;  // per vertex, -z_view
  std::vector<ScreenTriangle> triangles;
  VisibilityBuffer visibility;
  GBuffer target;
};

// How a pixel's motion came out: as projected, clamped to the guard band, or rejected.
enum class MotionStatus { Exact, Clamped, Rejected };

// Motion to the previous frame for a world point (w = 1) or a direction (w = 0, sky):
// previous pixel position minus the current pixel centre, both unjittered (cx, cy: the centre
// less the current jitter; `previous` has none), so motion excludes the jitter (render_channels.h).
// A point that was not in front of the previous camera's near plane has no previous pixel (its
// projection diverges as its view depth goes to 0, to millions of pixels): motion 0, Rejected.
// The sky counts as at the far plane. A point in front of it but far outside the previous view
// (beside the camera after a fast turn) keeps its direction, cut at the guard band one image
// size around the previous frame: still outside, so a consumer still sees no history there.
Vec2 motion_of(const FrameCamera& previous, Vec4 world, float cx, float cy, MotionStatus& status) {
  const Vec4 c = previous.view_projection * world;
  const float min_w = world.w != 0 ? previous.near_plane
                                   : previous.near_plane / previous.far_plane *
                                         std::sqrt(world.x * world.x + world.y * world.y + world.z * world.z);
  if (!(c.w >= min_w && c.w > 0)) {
    status = MotionStatus::Rejected;
    return {0, 0};
  }
  const Vec2 p = clip_to_pixel(previous, c);
  Vec2 m{p.x - cx, p.y - cy};
  const float w = static_cast<float>(previous.width), h = static_cast<float>(previous.height);
  float t = 1;  // the largest t <= 1 with (cx, cy) + t * m inside [-w, 2w] x [-h, 2h]
  if (m.x > 0) t = std::min(t, (2 * w - cx) / m.x);
  if (m.x < 0) t = std::min(t, (-w - cx) / m.x);
  if (m.y > 0) t = std::min(t, (2 * h - cy) / m.y);
  if (m.y < 0) t = std::min(t, (-h - cy) / m.y);
  status = t < 1 ? MotionStatus::Clamped : MotionStatus::Exact;
  return t < 1 ? m * t : m;
}

}  // namespace

Vec3 sky_color(const Sky& sky, Vec3 direction) {
  const float up = std::clamp(normalize(direction).y, 0.0f, 1.0f);
  return lerp(sky.horizon, sky.zenith, up);
}

SceneRenderer::SceneRenderer(const Scene& scene, const RenderSettings& settings)
    : settings_(settings), geometry_(scene) {
  CGSR_CHECK(settings.tile_size >= 4, "tile size must be at least 4");
  if (settings.shadow.map_size < 16)
    throw Error("render settings", "shadow map size " + config::out_of_range(settings.shadow.map_size, 16, config::kUnbounded));
  const Scene& s = geometry_.scene();
  shadow_maps_.resize(s.lights.size());
  if (settings.shadows)
    for (size_t i = 0; i < s.lights.size(); ++i)
      if (s.lights[i].shadows) shadow_maps_[i] = ShadowMap(geometry_, s.lights[i], settings.shadow);
  shader_ = std::make_unique<BlinnPhongShader>(s, shadow_maps_);
}

namespace {

// Vertex stage: world -> clip space of the current camera.
void transform_vertices(const SceneGeometry& g, RenderContext& ctx) {
  const size_t nv = g.vertex_count();
  ctx.clip.resize(nv);
  ctx.depth.resize(nv);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, nv, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t v = r.begin(); v < r.end(); ++v) {
      const Vec3 p = g.positions[v];
      ctx.clip[v] = ctx.camera.view_projection * Vec4{p.x, p.y, p.z, 1};
      ctx.depth[v] = ctx.clip[v].w;
    }
  });
}

// Triangle setup and rasterization: pixel space, near plane at w = near.
void rasterize_geometry(const SceneGeometry& g, float near_plane, int width, int height, int tile_size,
                        RenderContext& ctx) {
  RasterInput in;
  in.clip = &ctx.clip;
  in.depth = &ctx.depth;
  in.indices = &g.indices;
  in.cull_back = &g.cull_back;
  in.alpha_tested = &g.alpha_tested;
  in.w_min = near_plane;
  in.width = width;
  in.height = height;
  in.tile_size = tile_size;
  ctx.triangles = setup_triangles(in);
  rasterize(in, ctx.triangles, ctx.visibility,
            [&g](const ScreenTriangle& t, double x, double y) { return g.alpha_covers(t, x, y); });
}

// The G-buffer's planes, allocated at width x height, as raw pointers for the per-pixel writes.
struct GBufferPlanes {
  GBufferPlanes(GBuffer& out, int width, int height) {
    out.width = width;
    out.height = height;
    out.color = torch::empty({3, height, width}, torch::kFloat32);
    out.depth = torch::empty({1, height, width}, torch::kFloat32);
    out.normal = torch::empty({3, height, width}, torch::kFloat32);
    out.normal_angle = torch::empty({1, height, width}, torch::kFloat32);
    out.object_id = torch::empty({1, height, width}, torch::kInt32);
    out.material_id = torch::empty({1, height, width}, torch::kInt32);
    out.motion = torch::empty({2, height, width}, torch::kFloat32);
    plane = static_cast<size_t>(width) * height;
    color = out.color.data_ptr<float>();
    depth = out.depth.data_ptr<float>();
    normal = out.normal.data_ptr<float>();
    angle = out.normal_angle.data_ptr<float>();
    object = out.object_id.data_ptr<int32_t>();
    material = out.material_id.data_ptr<int32_t>();
    motion = out.motion.data_ptr<float>();
  }
  size_t plane = 0;
  float* color;
  float* depth;
  float* normal;
  float* angle;
  int32_t* object;
  int32_t* material;
  float* motion;
};

// No geometry (or a sky surface) at pixel p: the sky at infinity, moving with camera rotation
// only. Returns its linear colour.
Vec3 resolve_sky(const RenderContext& ctx, const Scene& scene, const GBufferPlanes& px, size_t p, float cx, float cy,
                 MotionStatus& motion) {
  const Vec3 ray = pixel_ray(ctx.camera, cx, cy);
  const Vec3 linear = sky_color(scene.sky, ray);
  px.depth[p] = std::numeric_limits<float>::infinity();
  for (int c = 0; c < 3; ++c) px.normal[c * px.plane + p] = 0;
  px.angle[p] = 0;
  px.object[p] = px.material[p] = -1;
  const Vec2 m = motion_of(ctx.previous, Vec4{ray.x, ray.y, ray.z, 0}, cx - ctx.camera.jitter.x,
                           cy - ctx.camera.jitter.y, motion);
  px.motion[p] = m.x;
  px.motion[px.plane + p] = m.y;
  return linear;
}

// A surface seen at pixel coordinates (cx, cy): its shaded linear colour (with fog), world point
// and normal (facing the camera).
struct ShadedPoint {
  Vec3 linear, world, normal;
};
ShadedPoint shade_surface(const RenderContext& ctx, const SceneGeometry& g, const SurfaceShader& shader,
                          const ScreenTriangle& tri, const Material& mat, float cx, float cy) {
  const FrameCamera& cam = ctx.camera;
  const Scene& scene = g.scene();
  // World space: perspective-correct interpolation of the original triangle's vertices.
  float b[3];
  tri.original_barycentrics(cx, cy, b);
  const uint32_t* idx = &g.indices[static_cast<size_t>(tri.triangle) * 3];
  auto interp3 = [&](const std::vector<Vec3>& a) { return a[idx[0]] * b[0] + a[idx[1]] * b[1] + a[idx[2]] * b[2]; };
  const Vec3 world = interp3(g.positions);
  Vec3 n = normalize(interp3(g.normals));
  if (!tri.front_facing) n = -n;  // two-sided surface seen from behind
  const Vec3 to_eye = normalize(cam.pose.position - world);
  if (length(n) == 0) n = to_eye;

  SurfacePoint s;
  s.position = world;
  s.normal = n;
  s.to_eye = to_eye;
  s.material = &mat;
  s.albedo = mat.tint * interp3(g.colors);
  if (mat.albedo_texture >= 0) {
    const UvFootprint f = uv_footprint(g, tri, cx, cy);
    const LinearRgba t = g.textures[mat.albedo_texture].sample_trilinear(f.uv, f.duv_dx, f.duv_dy);
    s.albedo = s.albedo * Vec3{t.r, t.g, t.b};
  }
  if (mat.lightmap_texture >= 0) {
    const Vec2 lm = g.lightmap_uvs[idx[0]] * b[0] + g.lightmap_uvs[idx[1]] * b[1] + g.lightmap_uvs[idx[2]] * b[2];
    const LinearRgba t = g.textures[mat.lightmap_texture].sample_bilinear_clamped(lm);
    s.lightmap = {t.r, t.g, t.b};
  }
  Vec3 linear = shader.shade(s);
  if (scene.fog.density > 0) {
    const float dist = length(world - cam.pose.position);
    const float f = 1.0f - std::exp(-scene.fog.density * std::max(0.0f, dist - scene.fog.start));
    linear = lerp(linear, scene.fog.color, f);
  }
  return {linear, world, n};
}

// A surface at pixel p: its shaded linear colour (with fog), returned, and its view-space depth,
// normal and angle, ids and motion written.
Vec3 resolve_surface(const RenderContext& ctx, const SceneGeometry& g, const SurfaceShader& shader,
                     const ScreenTriangle& tri, const Material& mat, const GBufferPlanes& px, size_t p, float cx,
                     float cy, MotionStatus& motion) {
  const FrameCamera& cam = ctx.camera;
  const ShadedPoint shaded = shade_surface(ctx, g, shader, tri, mat, cx, cy);
  const Vec3 world = shaded.world, n = shaded.normal;
  const Vec3 linear = shaded.linear;

  // View space: depth, normal and its angle to the direction towards the camera.
  px.depth[p] = ctx.visibility.depth[p];
  const Vec3 nv = normalize(cam.view.transform_direction(n));
  const Vec3 pv = cam.view.transform_point(world);
  const float cos_a = std::clamp(dot(nv, normalize(-pv)), -1.0f, 1.0f);
  px.normal[p] = nv.x;
  px.normal[px.plane + p] = nv.y;
  px.normal[2 * px.plane + p] = nv.z;
  px.angle[p] = std::min(1.0f, std::acos(cos_a) / kHalfPi);
  const Mesh& mesh = g.mesh_of(tri.triangle);
  px.object[p] = mesh.object_id;
  px.material[p] = mesh.material;
  const Vec2 m = motion_of(ctx.previous, Vec4{world.x, world.y, world.z, 1}, cx - ctx.camera.jitter.x,
                           cy - ctx.camera.jitter.y, motion);
  px.motion[p] = m.x;
  px.motion[px.plane + p] = m.y;
  return linear;
}

}  // namespace

GBuffer SceneRenderer::render(const CameraPose& pose, const CameraPose& previous, int width, int height,
                              float near_plane, float far_plane, Vec2 jitter) const {
  if (width <= 0) throw Error("render", "image width " + config::out_of_range(width, 1, config::kUnbounded));
  if (height <= 0) throw Error("render", "image height " + config::out_of_range(height, 1, config::kUnbounded));
  RenderContext ctx;
  ctx.camera = make_frame_camera(pose, width, height, near_plane, far_plane, jitter);
  ctx.previous = make_frame_camera(previous, width, height, near_plane, far_plane);  // motion excludes jitter
  const SceneGeometry& g = geometry_;
  transform_vertices(g, ctx);
  rasterize_geometry(g, near_plane, width, height, settings_.tile_size, ctx);

  // Resolve: one shading per visible pixel, tile by tile.
  GBuffer& out = ctx.target;
  const GBufferPlanes px(out, width, height);
  const int ts = settings_.tile_size;
  std::atomic<int64_t> rejected_total{0}, clamped_total{0};
  tbb::parallel_for(tbb::blocked_range2d<int>(0, height, ts, 0, width, ts), [&](const tbb::blocked_range2d<int>& r) {
    int64_t rejected_here = 0, clamped_here = 0;
    for (int i = r.rows().begin(); i < r.rows().end(); ++i)
      for (int j = r.cols().begin(); j < r.cols().end(); ++j) {
        const size_t p = static_cast<size_t>(i) * width + j;
        const float cx = j + 0.5f, cy = i + 0.5f;
        const int32_t si = ctx.visibility.screen_index[p];
        const ScreenTriangle* tri = si >= 0 ? &ctx.triangles[si] : nullptr;
        const Material* mat = tri ? &g.material_of(tri->triangle) : nullptr;
        MotionStatus motion = MotionStatus::Exact;
        const Vec3 linear = !tri || mat->sky ? resolve_sky(ctx, g.scene(), px, p, cx, cy, motion)
                                             : resolve_surface(ctx, g, *shader_, *tri, *mat, px, p, cx, cy, motion);
        rejected_here += motion == MotionStatus::Rejected;
        clamped_here += motion == MotionStatus::Clamped;
        px.color[p] = encode_srgb(linear.x);
        px.color[px.plane + p] = encode_srgb(linear.y);
        px.color[2 * px.plane + p] = encode_srgb(linear.z);
      }
    rejected_total += rejected_here;
    clamped_total += clamped_here;
  });
  out.motion_rejected = rejected_total.load();
  out.motion_clamped = clamped_total.load();

  out.edge = detect_edges(out.depth, out.normal, out.object_id, settings_.edges);
  return std::move(out);
}

torch::Tensor SceneRenderer::render_color(const CameraPose& pose, int width, int height, float near_plane,
                                          float far_plane, int samples) const {
  if (width <= 0) throw Error("render", "image width " + config::out_of_range(width, 1, config::kUnbounded));
  if (height <= 0) throw Error("render", "image height " + config::out_of_range(height, 1, config::kUnbounded));
  if (samples < 1 || samples > kMaxHrSamplesPerSide)
    throw Error("render", "samples per pixel side " + config::out_of_range(samples, 1, kMaxHrSamplesPerSide));
  const int n = samples, W = width * n, H = height * n;
  // The same projection at n x the size: its pixel coordinates are n x ours, so supersampled pixel
  // (sy, sx) is the sample at ((sx + 0.5) / n, (sy + 0.5) / n) of pixel (sy / n, sx / n).
  RenderContext ctx;
  ctx.camera = make_frame_camera(pose, W, H, near_plane, far_plane);
  ctx.previous = ctx.camera;
  const SceneGeometry& g = geometry_;
  transform_vertices(g, ctx);
  rasterize_geometry(g, near_plane, W, H, settings_.tile_size, ctx);

  torch::Tensor color = torch::empty({3, height, width}, torch::kFloat32);
  float* out = color.data_ptr<float>();
  const size_t plane = static_cast<size_t>(width) * height;
  const float weight = 1.0f / static_cast<float>(n * n);
  const int ts = std::max(1, settings_.tile_size / n);
  tbb::parallel_for(tbb::blocked_range2d<int>(0, height, ts, 0, width, ts), [&](const tbb::blocked_range2d<int>& r) {
    for (int i = r.rows().begin(); i < r.rows().end(); ++i)
      for (int j = r.cols().begin(); j < r.cols().end(); ++j) {
        Vec3 sum{};  // each pixel sums its samples in one order: independent of the threads
        for (int sy = i * n; sy < (i + 1) * n; ++sy)
          for (int sx = j * n; sx < (j + 1) * n; ++sx) {
            const float cx = static_cast<float>(sx) + 0.5f, cy = static_cast<float>(sy) + 0.5f;
            const int32_t si = ctx.visibility.screen_index[static_cast<size_t>(sy) * W + sx];
            const ScreenTriangle* tri = si >= 0 ? &ctx.triangles[si] : nullptr;
            const Material* mat = tri ? &g.material_of(tri->triangle) : nullptr;
            const Vec3 linear = !tri || mat->sky ? sky_color(g.scene().sky, pixel_ray(ctx.camera, cx, cy))
                                                 : shade_surface(ctx, g, *shader_, *tri, *mat, cx, cy).linear;
            sum += Vec3{std::clamp(linear.x, 0.0f, 1.0f), std::clamp(linear.y, 0.0f, 1.0f),
                        std::clamp(linear.z, 0.0f, 1.0f)};
          }
        const size_t p = static_cast<size_t>(i) * width + j;
        out[p] = encode_srgb(sum.x * weight);
        out[plane + p] = encode_srgb(sum.y * weight);
        out[2 * plane + p] = encode_srgb(sum.z * weight);
      }
  });
  return color;
}

namespace {

// The surfaces of one pixel's samples: triangles of one mesh that share a vertex and meet at
// less than the crease angle are one surface (a tessellated wall is not a border); anything else
// (another mesh, a crease, a fold of the same mesh, the sky) is another.
std::vector<int32_t> surface_labels(const SceneGeometry& g, const std::vector<int32_t>& triangles, float cos_crease) {
  std::vector<int32_t> distinct(triangles);
  std::sort(distinct.begin(), distinct.end());
  distinct.erase(std::unique(distinct.begin(), distinct.end()), distinct.end());
  std::vector<size_t> root(distinct.size());
  for (size_t i = 0; i < root.size(); ++i) root[i] = i;
  const auto find = [&](size_t i) {
    while (root[i] != i) i = root[i];
    return i;
  };
  const auto face_normal = [&](int32_t t) {
    const uint32_t* v = &g.indices[static_cast<size_t>(t) * 3];
    return normalize(cross(g.positions[v[1]] - g.positions[v[0]], g.positions[v[2]] - g.positions[v[0]]));
  };
  for (size_t i = 0; i < distinct.size(); ++i)
    for (size_t j = i + 1; j < distinct.size(); ++j) {
      const int32_t a = distinct[i], b = distinct[j];
      if (a < 0 || b < 0 || g.triangle_mesh[a] != g.triangle_mesh[b]) continue;
      const uint32_t* va = &g.indices[static_cast<size_t>(a) * 3];
      const uint32_t* vb = &g.indices[static_cast<size_t>(b) * 3];
      bool shared = false;
      for (int x = 0; x < 3; ++x)
        for (int y = 0; y < 3; ++y) shared |= va[x] == vb[y];
      if (shared && std::abs(dot(face_normal(a), face_normal(b))) >= cos_crease) root[find(j)] = find(i);
    }
  std::vector<int32_t> labels(triangles.size());
  for (size_t s = 0; s < triangles.size(); ++s) {
    const size_t i = std::lower_bound(distinct.begin(), distinct.end(), triangles[s]) - distinct.begin();
    labels[s] = distinct[find(i)];
  }
  return labels;
}

}  // namespace

BspBorderImage SceneRenderer::render_bsp_border(const CameraPose& pose, int width, int height, float near_plane,
                                                float far_plane, const BspBorderSettings& settings) const {
  check_bsp_border_settings(settings, width, height);
  const int m = settings.samples;
  // The view again at m x the size: the same projection, so its pixel coordinates are m x ours.
  RenderContext ctx;
  ctx.camera = make_frame_camera(pose, width * m, height * m, near_plane, far_plane);
  ctx.previous = ctx.camera;
  const SceneGeometry& g = geometry_;
  transform_vertices(g, ctx);
  rasterize_geometry(g, near_plane, width * m, height * m, settings_.tile_size, ctx);
  const int W2 = width * m;
  const float cos_crease = std::cos(settings_.edges.crease_angle * 3.14159265358979f / 180.0f);
  const Scene& scene = g.scene();

  // Screen triangles come out of setup in the order of the original triangles: a triangle's
  // pieces (after near-plane clipping) are a run found by binary search.
  struct ByTriangle {
    bool operator()(const ScreenTriangle& a, uint32_t t) const { return a.triangle < t; }
    bool operator()(uint32_t t, const ScreenTriangle& a) const { return t < a.triangle; }
  };
  CGSR_CHECK(std::is_sorted(ctx.triangles.begin(), ctx.triangles.end(),
                            [](const ScreenTriangle& a, const ScreenTriangle& b) { return a.triangle < b.triangle; }),
             "screen triangles out of triangle order");
  const auto pieces = [&](int32_t t) {
    return std::equal_range(ctx.triangles.begin(), ctx.triangles.end(), static_cast<uint32_t>(t), ByTriangle{});
  };

  // Each pixel reads its m x m samples and the ring of samples just outside it (its neighbours'
  // nearest): an edge that runs between two pixels' samples, closer than half a sample spacing to
  // their boundary, is still seen, and a leaf without samples of its own gets the ring's colour.
  struct WindowSample {
    int sx, sy;  // supersampled pixel
    bool own;
  };
  const int H2 = height * m;
  // Rows in parallel, each into its own list: the pixels come out in order whatever the threads.
  std::vector<std::vector<std::pair<int, BspTree>>> rows(height);
  tbb::parallel_for(0, height, [&](int i) {
    std::vector<WindowSample> window;
    std::vector<int32_t> tri;
    std::vector<float> depth;
    for (int j = 0; j < width; ++j) {
      window.clear();
      tri.clear();
      depth.clear();
      bool mixed = false;
      for (int sy = i * m - 1; sy <= i * m + m; ++sy)
        for (int sx = j * m - 1; sx <= j * m + m; ++sx) {
          if (sx < 0 || sy < 0 || sx >= W2 || sy >= H2) continue;
          const size_t p2 = static_cast<size_t>(sy) * W2 + sx;
          const int32_t si = ctx.visibility.screen_index[p2];
          const int32_t t = si >= 0 && !g.material_of(ctx.triangles[si].triangle).sky
                                ? static_cast<int32_t>(ctx.triangles[si].triangle)
                                : -1;
          window.push_back({sx, sy, sx >= j * m && sx < (j + 1) * m && sy >= i * m && sy < (i + 1) * m});
          tri.push_back(t);
          depth.push_back(si >= 0 ? ctx.visibility.depth[p2] : std::numeric_limits<float>::infinity());
          mixed |= t != tri.front();
        }
      if (!mixed) continue;
      const std::vector<int32_t> label = surface_labels(g, tri, cos_crease);
      if (std::all_of(label.begin(), label.end(), [&](int32_t l) { return l == label[0]; })) continue;

      // Candidates: the edges of every triangle seen that cross this pixel, the nearest
      // triangle's first on ties.
      std::map<int32_t, float> nearest;  // triangle -> its nearest sample depth
      for (size_t s = 0; s < tri.size(); ++s)
        if (tri[s] >= 0) {
          auto [it, inserted] = nearest.emplace(tri[s], depth[s]);
          if (!inserted) it->second = std::min(it->second, depth[s]);
        }
      std::vector<BspCandidate> candidates;
      for (const auto& [t, d] : nearest) {
        const auto [first, last] = pieces(t);
        for (auto piece = first; piece != last; ++piece)
          for (int k = 0; k < 3; ++k) {
            const int e = (k + 1) % 3;
            const auto line = line_through(piece->x[k] / m, piece->y[k] / m, piece->x[e] / m, piece->y[e] / m);
            // A line crosses the unit square when the centre is within half its extent along the normal.
            if (line && std::abs(line->side(j + 0.5, i + 0.5)) < 0.5 * (std::abs(line->a) + std::abs(line->b)))
              candidates.push_back({*line, d});
          }
      }
      if (candidates.empty()) continue;
      std::stable_sort(candidates.begin(), candidates.end(),
                       [](const BspCandidate& x, const BspCandidate& y) { return x.priority < y.priority; });

      std::vector<BspSample> samples(window.size());
      for (size_t s = 0; s < window.size(); ++s) {
        samples[s].x = (window[s].sx + 0.5) / m;
        samples[s].y = (window[s].sy + 0.5) / m;
        samples[s].surface = label[s];
        samples[s].own = window[s].own;
      }
      // The tree's shape does not depend on colour: shade only the samples of pixels that get one.
      if (!build_pixel_bsp(samples, candidates, settings.depth)) continue;
      for (size_t s = 0; s < window.size(); ++s) {
        const float cx = static_cast<float>(window[s].sx) + 0.5f, cy = static_cast<float>(window[s].sy) + 0.5f;
        Vec3 linear;
        if (tri[s] >= 0) {
          const ScreenTriangle& st = ctx.triangles[ctx.visibility.screen_index[static_cast<size_t>(window[s].sy) * W2 + window[s].sx]];
          linear = shade_surface(ctx, g, *shader_, st, g.material_of(st.triangle), cx, cy).linear;
        } else {
          linear = sky_color(scene.sky, pixel_ray(ctx.camera, cx, cy));
        }
        samples[s].color = {encode_srgb(linear.x), encode_srgb(linear.y), encode_srgb(linear.z)};
      }
      rows[i].emplace_back(i * width + j, std::move(*build_pixel_bsp(samples, candidates, settings.depth)));
    }
  });
  BspBorderImage out(width, height, settings.depth);
  for (auto& row : rows)
    for (auto& [pixel, tree] : row) out.add(pixel, std::move(tree));
  return out;
}

}  // namespace cgsr
