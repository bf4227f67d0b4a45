#pragma once
// A camera that moves through a level like a player: it visits the map's spawn points and items
// at eye height along a smooth spline, looking ahead along its way with slow yaw and pitch
// sways, and never passes through a wall.
//
// 1. Waypoints: every spawn point and item is dropped to the floor with the player's box (as the
//    game drops items) and lifted to eye height (player origin + 26; the origin is 24 above the
//    floor). A waypoint is dropped (and counted) when its box starts in solid, no floor is below
//    it, its eye is in a liquid or outside the playable space (no BSP cluster), or it is too
//    close to a drawn surface; waypoints closer than merge_distance to an earlier one are merged.
// 2. Navigation nodes: the centre of every BSP leaf of the playable space, dropped to the floor
//    the same way (and merged likewise), so routes can turn corners between waypoints.
// 3. Links: each node is linked to its nearest neighbours (up to max_link units away) when the
//    camera's box sweeps between them without touching a solid or player-clip brush
//    (bsp_trace.h) and the segment keeps `clearance` from every drawn surface
//    (surface_obstacles.h). Links are tested on demand.
// 4. Order: from a seeded spawn point, follow the shortest chain of links to the nearest
//    unvisited waypoint, and repeat. Waypoints no chain reaches are dropped (counted). When every
//    reachable waypoint is visited before the path is long enough, a new round starts. The route
//    is then shortened: a navigation node is skipped when the link around it is clear.
// 5. Spline: centripetal Catmull-Rom through the route, sampled every key_spacing units; each
//    span is checked sample to sample like a link. A span that touches something is retried with
//    its tangents halved, then as the straight link (known to be clear).
// 6. Orientation: look towards the point look_ahead units further along the path, turned by up to
//    open_space_degrees towards the longest free line of sight (players look down corridors, not
//    into the corner they are about to turn), averaged over the neighbouring keys and turning at a
//    bounded rate, plus sine sways of yaw and pitch with seeded phases; pitch is clamped.
// Everything here is in Quake space (Z up, game units, yaw counter-clockwise from +X, pitch
// positive up).

#include <cstdint>
#include <string>
#include <vector>

#include "render_data/q3/bsp_trace.h"
#include "render_data/q3/entities.h"
#include "render_data/q3/surface_obstacles.h"

namespace cgsr::q3 {

struct CameraPathOptions {
  float length = 3000;          // game units of travel to lay out
  float eye_height = 26;        // above the player origin
  Vec3 hull_half{16, 16, 8};    // the camera's box for brush traces
  float clearance = 12;         // distance kept from drawn surfaces
  float max_link = 1536;        // longest straight link between two waypoints
  float merge_distance = 48;    // waypoints closer than this are one
  int neighbours = 12;          // links tested per node (nearest first)
  float key_spacing = 8;        // distance between path keys
  float look_ahead = 160;       // the camera looks at the path this far ahead
  float yaw_sway_degrees = 20, yaw_sway_period = 1500;    // period in units of travel
  float pitch_sway_degrees = 8, pitch_sway_period = 900;
  float max_pitch = 45;         // |pitch| limit, degrees
  float max_turn_rate = 0.6f;   // degrees of yaw per unit of travel (pitch: half of it)
  float open_space_degrees = 45;  // the heading may turn this far towards a longer line of sight
  uint64_t seed = 0;
};

struct CameraPathReport {
  int candidates = 0;  // spawn points and items with an origin
  int dropped_in_solid = 0, dropped_no_floor = 0, dropped_in_liquid = 0, dropped_outside = 0,
      dropped_near_surface = 0;
  int merged = 0;
  int dropped_unreachable = 0;   // no chain of links reaches them from the start
  int waypoints = 0;             // usable waypoints (after drops and merges)
  int navigation_nodes = 0;      // from BSP leaves
  int visited = 0;               // waypoint visits on the path (repeats included)
  int softened_spans = 0;        // spans whose tangents were halved
  int straightened_spans = 0;    // spans that became the straight link
  float length = 0;              // of the laid-out path
  bool turntable = false;        // a single reachable waypoint: the camera turns on the spot
  int dropped() const {
    return dropped_in_solid + dropped_no_floor + dropped_in_liquid + dropped_outside + dropped_near_surface +
           dropped_unreachable;
  }
  std::string summary() const;
};

struct QuakeCameraKey {
  Vec3 position;
  float yaw = 0, pitch = 0;  // degrees; yaw is continuous (not wrapped)
  double distance = 0;       // along the path (strictly increasing)
};

struct QuakeCameraPath {
  std::vector<QuakeCameraKey> keys;
  CameraPathReport report;
};

// `context` names the map in errors (e.g. no usable waypoint at all).
QuakeCameraPath build_camera_path(const std::vector<Entity>& entities, const BspCollision& collision,
                                  const SurfaceObstacles& obstacles, const CameraPathOptions& options,
                                  const std::string& context);

}  // namespace cgsr::q3
