#pragma once
// The software renderer: a scene prepared once (flattened geometry, mip chains, shadow maps),
// then any number of frames rendered independently at any resolution. No global state: each
// render() call builds its own RenderContext (camera, matrices, visibility buffer, target
// G-buffer), so frames and resolutions may render concurrently.
//
// Per frame: vertex stage (world -> clip space), triangle setup and tile-parallel rasterization
// (raster_core.h, pixel space), then a tile-parallel resolve that shades each visible pixel
// once (shading.h, world space), applies fog, writes the G-buffer (view space) and motion
// vectors (reprojection into the previous camera's pixel space), then edges (edges.h).

#include <memory>
#include <vector>

#include "render_data/bsp_border_builder.h"
#include "render_data/camera.h"
#include "render_data/edges.h"
#include "render_data/gbuffer.h"
#include "render_data/scene_geometry.h"
#include "render_data/shading.h"
#include "render_data/shadow_maps.h"

namespace cgsr {

struct RenderSettings {
  bool shadows = true;  // shadow maps for lights with Light::shadows
  ShadowSettings shadow;
  EdgeSettings edges;
  int tile_size = 32;  // pixels per side of a raster tile
};

class SceneRenderer {
 public:
  SceneRenderer(const Scene& scene, const RenderSettings& settings);

  // Renders the view from `pose` at width x height. `previous` is the camera of the previous
  // frame (motion vectors reproject each pixel's world point into it; pass `pose` for none).
  // `jitter`: the sub-pixel offset of this frame's projection in pixels (jitter.h); the motion
  // vectors exclude it (a still camera over a static scene has motion 0 whatever the jitter).
  GBuffer render(const CameraPose& pose, const CameraPose& previous, int width, int height, float near_plane,
                 float far_plane, Vec2 jitter = {0, 0}) const;

  // Only the colour of the view from `pose` at width x height, with samples x samples samples per
  // pixel (hr_samples.h): the view rasterized at samples x the size, each sample shaded as render()
  // shades a pixel centre (with fog, or the sky) and clamped to [0, 1] (what it displays as), the
  // pixel's samples averaged in linear light (a box filter), then sRGB-encoded: float32 [3,H,W] as
  // GBuffer::color. Samples 1 is render()'s colour. Unjittered: it is ground truth.
  torch::Tensor render_color(const CameraPose& pose, int width, int height, float near_plane, float far_plane,
                             int samples) const;

  // The sub-pixel BSP border image (bsp_border.h) of the same view at width x height: the view is
  // rasterized again at settings.samples x the size, so every pixel gets samples^2 samples of which
  // triangle is visible (plus the ring of its neighbours' nearest samples); a pixel whose samples
  // see more than one surface (different meshes, or triangles of a mesh that meet at a crease or
  // do not touch) gets a BSP whose candidate lines are the projected edges of the triangles it
  // sees that cross it, its leaves the mean colour of their samples, each shaded as render()
  // shades a pixel centre. Deterministic and independent of the thread count (docs/bsp_border.md).
  BspBorderImage render_bsp_border(const CameraPose& pose, int width, int height, float near_plane, float far_plane,
                                   const BspBorderSettings& settings) const;

  const SceneGeometry& geometry() const { return geometry_; }
  const RenderSettings& settings() const { return settings_; }

 private:
  RenderSettings settings_;
  SceneGeometry geometry_;
  std::vector<ShadowMap> shadow_maps_;  // one per scene light
  std::unique_ptr<SurfaceShader> shader_;
};

// Sky colour seen along a world-space direction (scene.h Sky), linear RGB.
Vec3 sky_color(const Sky& sky, Vec3 direction);

}  // namespace cgsr
