#include "render_data/q3/bsp_trace.h"

#include <algorithm>
#include <cmath>

namespace cgsr::q3 {
namespace {

// Distance kept between a stopped box and the plane it touched, as in the game.
constexpr float kSurfaceEpsilon = 0.125f;

// How far the box reaches along the plane normal from its centre.
float box_reach(Vec3 normal, Vec3 half) {
  return std::fabs(normal.x) * half.x + std::fabs(normal.y) * half.y + std::fabs(normal.z) * half.z;
}

}  // namespace

struct BspCollision::Sweep {
  Vec3 start, end, half;
  TraceResult result;
};

BspCollision::BspCollision(const BspFile& bsp, int mask) : bsp_(bsp), mask_(mask), checked_(bsp.brushes.size(), 0) {
  for (size_t m = 1; m < bsp.models.size(); ++m)
    for (int b = 0; b < bsp.models[m].brush_count; ++b) {
      const int brush = bsp.models[m].first_brush + b;
      if (bsp.textures[bsp.brushes[brush].texture].contents & mask_) model_brushes_.push_back(brush);
    }
}

TraceResult BspCollision::trace(Vec3 start, Vec3 end, Vec3 half_extents) const {
  if (++trace_id_ == 0) {  // wrapped: forget every mark
    std::fill(checked_.begin(), checked_.end(), 0);
    trace_id_ = 1;
  }
  Sweep sweep;
  sweep.start = start;
  sweep.end = end;
  sweep.half = half_extents;
  trace_node(0, sweep);
  for (int brush : model_brushes_) clip_brush(brush, sweep);
  TraceResult& r = sweep.result;
  r.end = r.fraction >= 1.0f ? end : lerp(start, end, r.fraction);
  return r;
}

bool BspCollision::box_in_solid(Vec3 center, Vec3 half_extents) const {
  return trace(center, center, half_extents).start_solid;
}

int BspCollision::leaf_at(Vec3 point) const {
  int node = 0;
  while (node >= 0) {
    const BspNode& n = bsp_.nodes[node];
    const BspPlane& p = bsp_.planes[n.plane];
    node = n.children[dot(p.normal, point) - p.dist >= 0 ? 0 : 1];
  }
  return -node - 1;
}

void BspCollision::trace_node(int node, Sweep& sweep) const {
  if (node < 0) {
    const BspLeaf& leaf = bsp_.leafs[-node - 1];
    for (int i = 0; i < leaf.leaf_brush_count; ++i) {
      const int brush = bsp_.leaf_brushes[leaf.first_leaf_brush + i];
      if (checked_[brush] == trace_id_) continue;
      checked_[brush] = trace_id_;
      if (bsp_.textures[bsp_.brushes[brush].texture].contents & mask_) clip_brush(brush, sweep);
    }
    return;
  }
  // Descend into the side(s) of the splitting plane the swept box touches. The segment is not
  // split: brushes are clipped exactly in the leaves, this only prunes the tree.
  const BspNode& n = bsp_.nodes[node];
  const BspPlane& plane = bsp_.planes[n.plane];
  const float reach = box_reach(plane.normal, sweep.half) + 1.0f;
  const float d1 = dot(plane.normal, sweep.start) - plane.dist, d2 = dot(plane.normal, sweep.end) - plane.dist;
  if (d1 >= reach && d2 >= reach) return trace_node(n.children[0], sweep);
  if (d1 < -reach && d2 < -reach) return trace_node(n.children[1], sweep);
  trace_node(n.children[0], sweep);
  trace_node(n.children[1], sweep);
}

// The swept box against one convex brush: the box enters the brush at the latest entering plane
// and leaves it at the earliest leaving plane; it hits when it enters before it leaves.
void BspCollision::clip_brush(int brush_index, Sweep& sweep) const {
  const BspBrush& brush = bsp_.brushes[brush_index];
  if (brush.side_count == 0) return;
  float enter = -1.0f, leave = 1.0f;
  bool starts_out = false, ends_out = false;
  Vec3 hit_normal;
  for (int s = 0; s < brush.side_count; ++s) {
    const BspPlane& plane = bsp_.planes[bsp_.brush_sides[brush.first_side + s].plane];
    const float dist = plane.dist + box_reach(plane.normal, sweep.half);
    const float d1 = dot(sweep.start, plane.normal) - dist, d2 = dot(sweep.end, plane.normal) - dist;
    if (d2 > 0) ends_out = true;
    if (d1 > 0) starts_out = true;
    // Entirely in front of one face: the segment never gets inside this brush.
    if (d1 > 0 && (d2 >= kSurfaceEpsilon || d2 >= d1)) return;
    if (d1 <= 0 && d2 <= 0) continue;
    if (d1 > d2) {  // entering
      const float f = std::max(0.0f, (d1 - kSurfaceEpsilon) / (d1 - d2));
      if (f > enter) {
        enter = f;
        hit_normal = plane.normal;
      }
    } else {  // leaving
      const float f = std::min(1.0f, (d1 + kSurfaceEpsilon) / (d1 - d2));
      if (f < leave) leave = f;
    }
  }
  TraceResult& r = sweep.result;
  if (!starts_out) {
    r.start_solid = true;
    if (!ends_out) r.fraction = 0.0f;
    return;
  }
  if (enter < leave && enter > -1.0f && enter < r.fraction) {
    r.fraction = std::max(0.0f, enter);
    r.normal = hit_normal;
  }
}

}  // namespace cgsr::q3
