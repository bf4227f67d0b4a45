#pragma once
// Collision against a map's brushes, as the game moves players: an axis-aligned box swept along a
// segment stops at the first brush whose contents block it. The world's brushes are found through
// the BSP tree (only the leaves the swept box touches are visited); the brushes of the other
// models (doors, platforms: drawn at their resting place) are tested directly.
// Everything here is in Quake space (Z up, game units).
//
// Not thread-safe: a trace marks the brushes it has tested in per-instance scratch memory.

#include <cstdint>
#include <vector>

#include "render_data/q3/bsp_file.h"

namespace cgsr::q3 {

struct TraceResult {
  float fraction = 1.0f;     // how far along the segment the box got before touching a brush
  bool start_solid = false;  // the box starts inside a blocking brush
  Vec3 end;                  // start + fraction * (end - start)
  Vec3 normal;               // of the plane that stopped it (when fraction < 1)
  bool hit() const { return start_solid || fraction < 1.0f; }
};

class BspCollision {
 public:
  // `bsp` must outlive this object. Brushes block when their contents share a bit with `mask`.
  explicit BspCollision(const BspFile& bsp, int mask = contents::kSolid | contents::kPlayerClip);

  // Sweeps the box [-half, +half] around a point moving from `start` to `end`.
  TraceResult trace(Vec3 start, Vec3 end, Vec3 half_extents) const;
  bool box_in_solid(Vec3 center, Vec3 half_extents) const;
  // The world leaf holding `point`, and its cluster (-1: outside the playable space).
  int leaf_at(Vec3 point) const;
  int cluster_at(Vec3 point) const { return bsp_.leafs[leaf_at(point)].cluster; }
  const BspFile& bsp() const { return bsp_; }
  int mask() const { return mask_; }

 private:
  struct Sweep;
  void trace_node(int node, Sweep& sweep) const;
  void clip_brush(int brush, Sweep& sweep) const;

  const BspFile& bsp_;
  int mask_;
  std::vector<int> model_brushes_;         // brushes of models 1..n that block
  mutable std::vector<uint32_t> checked_;  // per brush: the trace that last tested it
  mutable uint32_t trace_id_ = 0;
};

}  // namespace cgsr::q3
