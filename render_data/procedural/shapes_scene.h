#pragma once
// The "shapes" scene source: random flat geometric shapes in front of a background plane, the
// training images of SRPO-style networks (super-resolution of aliased, rasterized edges). Every
// shape is real geometry, so each resolution of a render is its own aliased rasterization (one
// sample per pixel) with the usual G-buffers: depth, normals, ids, edges, motion.
//
//   scene:
//     type: shapes
//     counts: {triangles: 8, quads: 6, discs: 5, polygons: 4, rings: 3, bars: 6, curves: 4}
//     size: [0.05, 0.4]           # a shape's extent, fraction of the view height
//     thickness: [0.004, 0.03]    # bars, rings and curves, fraction of the view height
//     depth_range: 0.3            # shapes lie between (1 - depth_range) and 1 x the background distance
//     gradients: 0.3              # chance that a shape (or the background) has a two-colour gradient
//     textured: 0.1               # chance that it has a procedural texture
//     camera: {vfov: 50, drift: 0.15, dolly: 0.05, roll: 3, keys: 3}
//
// The camera looks along -z at a background plane 10 m away; shapes face it at distinct depths
// (no z-fighting; nearer ones cover farther ones), placed and sized in screen terms so the counts
// and sizes mean the same at any field of view. The scene covers any aspect ratio up to 16:9
// plus the camera's drift, so some shapes of wide areas lie outside a 4:3 view. Colours are
// unlit (a flat colour renders as exactly that colour). The camera drifts slowly over the
// sequence (a smooth path through `keys` random poses), so consecutive frames differ by a
// sub-pixel to few-pixel motion with parallax between the depth layers. Same options + seed =
// same scene; `variant: N` gives another scene of the same seed.

#include <cstdint>
#include <string>
#include <vector>

#include "core/config.h"
#include "render_data/scene.h"
#include "render_data/scene_source.h"

namespace cgsr {

struct ShapeCounts {
  int triangles = 8;  // random triangles (no slivers)
  int quads = 6;      // random convex quadrilaterals
  int discs = 5;      // circles (64-gons: smooth at any resolution used here)
  int polygons = 4;   // regular polygons, 3 to 8 sides
  int rings = 3;      // annuli
  int bars = 6;       // thin straight bars (lines)
  int curves = 4;     // thin quadratic Bezier strokes
  int total() const { return triangles + quads + discs + polygons + rings + bars + curves; }
};

struct ShapesCamera {
  float vfov = 50.0f;   // vertical field of view, degrees
  float drift = 0.15f;  // how far the camera wanders, fraction of the view height at the background
  float dolly = 0.05f;  // forward/back wandering, fraction of the background distance
  float roll = 3.0f;    // degrees of roll either way
  int keys = 3;         // random poses the path passes through (more: a more winding path)
};

struct ShapesOptions {
  std::string name = "shapes";
  int variant = 0;  // 0: the scene of the render seed; N: another scene of the same seed
  ShapeCounts counts;
  std::vector<float> size = {0.05f, 0.4f};         // [lo, hi] extent, fraction of the view height
  std::vector<float> thickness = {0.004f, 0.03f};  // [lo, hi] stroke width, fraction of the view height
  float depth_range = 0.3f;
  float gradients = 0.3f;
  float textured = 0.1f;
  int texture_size = 64;  // texels per side of each procedural texture
  ShapesCamera camera;
};

config::Schema<ShapesOptions> shapes_schema();

SceneBundle make_shapes_scene(const ShapesOptions& options, uint64_t seed);

// Adds "shapes" to a scene-source registry (scene_sources() does, when it is first used).
void register_shapes_scene_source(Registry<SceneSourceFactory>& registry);

}  // namespace cgsr
