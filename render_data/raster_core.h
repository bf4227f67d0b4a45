#pragma once
// The triangle pipeline shared by camera views and shadow maps: near-plane clipping in clip space,
// projection to pixel coordinates, tile binning and tile-parallel rasterization into a
// visibility buffer (nearest depth + which triangle covers each pixel centre). Shading happens
// afterwards, once per pixel, from the visibility buffer (renderer.cpp).
//
// Coverage rule: a pixel (i, j) is covered when its centre (j + 0.5, i + 0.5) is inside the
// triangle; centres exactly on an edge belong to the triangle whose edge is a top or left edge
// (the Direct3D/OpenGL convention), so triangles sharing an edge never both cover a centre and
// never leave a gap. One sample per pixel, no anti-aliasing.

#include <cstdint>
#include <functional>
#include <vector>

#include "render_data/vec_math.h"

namespace cgsr {

// Input: clip-space vertices, per-vertex depth attribute (what the depth test compares:
// -z_view for perspective views, distance along the light for orthographic shadow maps) and
// indexed triangles.
struct RasterInput {
  const std::vector<Vec4>* clip = nullptr;
  const std::vector<float>* depth = nullptr;
  const std::vector<uint32_t>* indices = nullptr;   // three per triangle
  const std::vector<uint8_t>* cull_back = nullptr;  // per triangle: 1 = drop back faces
  // Per triangle: 1 = ask `coverage_test` for each covered centre (alpha-tested materials).
  const std::vector<uint8_t>* alpha_tested = nullptr;
  float w_min = 1e-6f;  // clip plane w >= w_min (the near plane of a perspective view: w_min = near)
  int width = 0, height = 0;
  int tile_size = 32;
};

// A triangle after clipping, in pixel coordinates (x right, y down).
struct ScreenTriangle {
  double x[3], y[3];      // pixel coordinates of the three vertices, counter-clockwise on screen
  float inv_w[3];         // 1 / clip.w per vertex
  float depth[3];         // depth attribute per vertex
  float bary[3][3];       // barycentrics of each vertex w.r.t. the original (unclipped) triangle
  double inv_area = 0;    // 1 / (twice the signed area), > 0
  uint32_t triangle = 0;  // index of the original triangle
  bool front_facing = true;  // counter-clockwise in view space (y up)
  int x0 = 0, x1 = -1, y0 = 0, y1 = -1;  // inclusive pixel bounds, clamped to the image

  // Barycentrics of the original triangle at pixel coordinates (px, py), perspective-correct.
  // Valid outside the triangle too (extrapolated), which gives screen-space derivatives.
  void original_barycentrics(double px, double py, float out[3]) const;
  // Depth attribute at (px, py), perspective-correct.
  float depth_at(double px, double py) const;
};

struct VisibilityBuffer {
  int width = 0, height = 0;
  std::vector<float> depth;           // depth attribute of the nearest surface; +inf where empty
  std::vector<int32_t> screen_index;  // index into the ScreenTriangle list; -1 where empty
};

// Decides whether an alpha-tested triangle covers a pixel centre (px, py).
using CoverageTest = std::function<bool(const ScreenTriangle& tri, double px, double py)>;

// Clips, projects and culls every triangle (vertex order within the output is deterministic).
std::vector<ScreenTriangle> setup_triangles(const RasterInput& input);

// Depth test and coverage into `out` (resized and cleared here). Tiles run in parallel (TBB);
// within a tile triangles are drawn in order with a strict less-than depth test, so the result
// does not depend on the thread count.
void rasterize(const RasterInput& input, const std::vector<ScreenTriangle>& triangles, VisibilityBuffer& out,
               const CoverageTest& coverage_test = {});

}  // namespace cgsr
