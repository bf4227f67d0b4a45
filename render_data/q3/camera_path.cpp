#include "render_data/q3/camera_path.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <queue>
#include <random>
#include <sstream>

#include "core/error.h"
#include "render_data/vec_math.h"

namespace cgsr::q3 {
namespace {

constexpr float kDeg = 180.0f / kPiF;
const Vec3 kPlayerHalf{15, 15, 24};  // the player's box around its origin (24 above the floor)

struct Node {
  Vec3 eye;
  bool target = false;  // a spawn point or item (navigation nodes only lead to them)
  bool spawn = false;
};

// Whether the camera may move along the segment: brushes (box sweep) and drawn surfaces.
class Clearance {
 public:
  Clearance(const BspCollision& collision, const SurfaceObstacles& obstacles, const CameraPathOptions& o)
      : collision_(collision), obstacles_(obstacles), o_(o) {}
  bool segment(Vec3 a, Vec3 b) const {
    return !collision_.trace(a, b, o_.hull_half).hit() && obstacles_.segment_clear(a, b, o_.clearance);
  }

 private:
  const BspCollision& collision_;
  const SurfaceObstacles& obstacles_;
  const CameraPathOptions& o_;
};

enum class Placement { Ok, InSolid, NoFloor, InLiquid, Outside, NearSurface };

// Drops a player standing around `origin` to the floor and returns its eye.
class EyePlacer {
 public:
  EyePlacer(const BspCollision& collision, const SurfaceObstacles& obstacles, const CameraPathOptions& o)
      : collision_(collision),
        liquids_(collision.bsp(), contents::kLava | contents::kSlime | contents::kWater),
        obstacles_(obstacles),
        o_(o) {}

  Placement place(Vec3 origin, Vec3& eye) const {
    // Item origins sit about 16 units above the floor, spawn points about 24 or higher, and
    // mappers are not exact: the first height where a player fits is dropped to the floor.
    Vec3 start;
    bool fits = false;
    for (float lift : {8.0f, 24.0f, 40.0f, 0.0f}) {
      start = origin + Vec3{0, 0, lift};
      if ((fits = !collision_.box_in_solid(start, kPlayerHalf))) break;
    }
    if (!fits) return Placement::InSolid;
    const TraceResult fall = collision_.trace(start, start - Vec3{0, 0, 1024}, kPlayerHalf);
    if (!fall.hit()) return Placement::NoFloor;
    eye = fall.end + Vec3{0, 0, o_.eye_height};
    if (collision_.box_in_solid(eye, o_.hull_half)) return Placement::InSolid;
    if (liquids_.box_in_solid(eye, o_.hull_half) || liquids_.box_in_solid(fall.end, kPlayerHalf))
      return Placement::InLiquid;
    if (collision_.cluster_at(eye) < 0) return Placement::Outside;
    if (obstacles_.distance(eye, o_.clearance) < o_.clearance) return Placement::NearSurface;
    return Placement::Ok;
  }

 private:
  const BspCollision& collision_;
  BspCollision liquids_;
  const SurfaceObstacles& obstacles_;
  const CameraPathOptions& o_;
};

bool near_any(const std::vector<Node>& nodes, Vec3 p, float distance) {
  return std::any_of(nodes.begin(), nodes.end(), [&](const Node& n) { return length(n.eye - p) < distance; });
}

std::vector<Node> collect_targets(const std::vector<Entity>& entities, const EyePlacer& placer,
                                  const CameraPathOptions& o, const std::string& context, CameraPathReport& report) {
  std::vector<Node> out;
  for (const Entity& e : entities) {
    const bool spawn = is_spawn_point(e);
    if (!spawn && !is_item(e)) continue;
    const auto origin = e.vector("origin", context);
    if (!origin) continue;
    ++report.candidates;
    Vec3 eye;
    switch (placer.place(*origin, eye)) {
      case Placement::InSolid: ++report.dropped_in_solid; continue;
      case Placement::NoFloor: ++report.dropped_no_floor; continue;
      case Placement::InLiquid: ++report.dropped_in_liquid; continue;
      case Placement::Outside: ++report.dropped_outside; continue;
      case Placement::NearSurface: ++report.dropped_near_surface; continue;
      case Placement::Ok: break;
    }
    if (near_any(out, eye, o.merge_distance)) {
      ++report.merged;
      continue;
    }
    out.push_back({eye, true, spawn});
  }
  report.waypoints = static_cast<int>(out.size());
  return out;
}

// Leaf centres of the playable space, at eye height above their floor.
void add_navigation_nodes(const BspFile& bsp, const EyePlacer& placer, const CameraPathOptions& o,
                          std::vector<Node>& nodes, CameraPathReport& report) {
  for (const BspLeaf& leaf : bsp.leafs) {
    if (leaf.cluster < 0) continue;
    const Vec3 centre{0.5f * (leaf.mins[0] + leaf.maxs[0]), 0.5f * (leaf.mins[1] + leaf.maxs[1]),
                      0.5f * (leaf.mins[2] + leaf.maxs[2])};
    Vec3 eye;
    if (placer.place(centre, eye) != Placement::Ok || near_any(nodes, eye, o.merge_distance)) continue;
    nodes.push_back({eye, false, false});
    ++report.navigation_nodes;
  }
}

// Each node linked to its nearest neighbours; links are tested on demand and remembered.
class LinkGraph {
 public:
  LinkGraph(const std::vector<Node>& nodes, const Clearance& clear, const CameraPathOptions& o)
      : nodes_(nodes), clear_(clear), candidates_(nodes.size()) {
    const int n = static_cast<int>(nodes.size());
    for (int a = 0; a < n; ++a) {
      std::vector<std::pair<float, int>> near;
      for (int b = 0; b < n; ++b)
        if (b != a && distance(a, b) <= o.max_link) near.push_back({distance(a, b), b});
      const size_t k = std::min(near.size(), static_cast<size_t>(o.neighbours));
      std::partial_sort(near.begin(), near.begin() + k, near.end());
      for (size_t i = 0; i < k; ++i) {  // symmetric: b may link to a even if a is not among b's nearest
        candidates_[a].push_back(near[i].second);
        candidates_[near[i].second].push_back(a);
      }
    }
    for (auto& list : candidates_) {
      std::sort(list.begin(), list.end());
      list.erase(std::unique(list.begin(), list.end()), list.end());
    }
  }

  float distance(int a, int b) const { return length(nodes_[a].eye - nodes_[b].eye); }

  bool linked(int a, int b) {
    const auto key = std::minmax(a, b);
    const auto it = cache_.find(key);
    if (it != cache_.end()) return it->second;
    return cache_[key] = clear_.segment(nodes_[a].eye, nodes_[b].eye);
  }

  // Shortest chain of links from `from` to the nearest node accepted by `want`: the nodes after
  // `from`, or empty when none is reachable.
  template <class Want>
  std::vector<int> route_to_nearest(int from, Want want) {
    const int n = static_cast<int>(nodes_.size());
    std::vector<float> dist(n, std::numeric_limits<float>::infinity());
    std::vector<int> previous(n, -1);
    using Item = std::pair<float, int>;
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
    dist[from] = 0;
    queue.push({0, from});
    while (!queue.empty()) {
      const auto [d, node] = queue.top();
      queue.pop();
      if (d > dist[node]) continue;
      if (node != from && want(node)) {
        std::vector<int> route;
        for (int at = node; at != from; at = previous[at]) route.push_back(at);
        std::reverse(route.begin(), route.end());
        return route;
      }
      for (int next : candidates_[node]) {
        const float nd = d + distance(node, next);
        if (nd < dist[next] && linked(node, next)) {
          dist[next] = nd;
          previous[next] = node;
          queue.push({nd, next});
        }
      }
    }
    return {};
  }

  // Which nodes some chain of links connects to `from`.
  std::vector<char> reachable_from(int from) {
    std::vector<char> seen(nodes_.size(), 0);
    std::vector<int> queue{from};
    seen[from] = 1;
    for (size_t q = 0; q < queue.size(); ++q)
      for (int next : candidates_[queue[q]])
        if (!seen[next] && linked(queue[q], next)) {
          seen[next] = 1;
          queue.push_back(next);
        }
    return seen;
  }

 private:
  const std::vector<Node>& nodes_;
  const Clearance& clear_;
  std::vector<std::vector<int>> candidates_;
  std::map<std::pair<int, int>, bool> cache_;
};

// Visits the nearest unvisited target (by route) again and again until the route is `needed` long.
std::vector<int> plan_route(const std::vector<Node>& nodes, LinkGraph& graph, float needed, int start,
                            CameraPathReport& report) {
  const int n = static_cast<int>(nodes.size());
  std::vector<int> route{start};
  std::vector<char> visited(n, 0);
  visited[start] = 1;
  float travelled = 0;
  bool progressed = false;
  while (travelled < needed) {
    const std::vector<int> step =
        graph.route_to_nearest(route.back(), [&](int i) { return nodes[i].target && !visited[i]; });
    if (step.empty()) {
      // Every reachable target is visited: another round, unless the last one went nowhere.
      if (!progressed) break;
      progressed = false;
      std::fill(visited.begin(), visited.end(), 0);
      visited[route.back()] = 1;
      continue;
    }
    for (int node : step) {
      travelled += graph.distance(route.back(), node);
      route.push_back(node);
    }
    visited[step.back()] = 1;
    ++report.visited;
    progressed = true;
  }
  const std::vector<char> reachable = graph.reachable_from(start);
  for (int i = 0; i < n; ++i)
    if (nodes[i].target && !reachable[i]) ++report.dropped_unreachable;
  return route;
}

// Skips navigation nodes where the straight link around them is clear (targets are kept).
std::vector<Vec3> shorten(const std::vector<Node>& nodes, const std::vector<int>& route, const Clearance& clear,
                          float max_link) {
  std::vector<Vec3> out{nodes[route[0]].eye};
  size_t i = 0;
  while (i + 1 < route.size()) {
    size_t j = i + 1;
    // Extend past navigation nodes while the direct segment stays clear.
    while (j + 1 < route.size() && !nodes[route[j]].target &&
           length(nodes[route[j + 1]].eye - nodes[route[i]].eye) <= max_link &&
           clear.segment(nodes[route[i]].eye, nodes[route[j + 1]].eye))
      ++j;
    out.push_back(nodes[route[j]].eye);
    i = j;
  }
  return out;
}

// One span of a centripetal Catmull-Rom spline as a cubic Hermite curve, tangents scaled.
struct CurveSegment {
  Vec3 p0, p1, m0, m1;
  Vec3 at(float s) const {
    const float s2 = s * s, s3 = s2 * s;
    return p0 * (2 * s3 - 3 * s2 + 1) + m0 * (s3 - 2 * s2 + s) + p1 * (-2 * s3 + 3 * s2) + m1 * (s3 - s2);
  }
};

CurveSegment centripetal_span(const std::vector<Vec3>& p, size_t i) {
  const size_t n = p.size();
  auto knot = [](Vec3 a, Vec3 b) { return std::max(1e-3f, std::sqrt(length(b - a))); };
  const Vec3 a = p[i], b = p[i + 1];
  const float d12 = knot(a, b);
  // Tangent at a point from its neighbours on non-uniform knots (the chord at path ends).
  auto tangent = [&](size_t k) -> Vec3 {
    if (k == 0 || k + 1 >= n) return k == 0 ? (p[1] - p[0]) * (1.0f / knot(p[0], p[1]))
                                            : (p[n - 1] - p[n - 2]) * (1.0f / knot(p[n - 2], p[n - 1]));
    const float d0 = knot(p[k - 1], p[k]), d1 = knot(p[k], p[k + 1]);
    return (p[k] - p[k - 1]) * (1.0f / d0) - (p[k + 1] - p[k - 1]) * (1.0f / (d0 + d1)) + (p[k + 1] - p[k]) * (1.0f / d1);
  };
  return {a, b, tangent(i) * d12, tangent(i + 1) * d12};
}

float wrap180(float degrees) {
  degrees = std::fmod(degrees + 180.0f, 360.0f);
  if (degrees < 0) degrees += 360.0f;
  return degrees - 180.0f;
}

// Point at arc length s along a polyline with cumulative lengths `cum`.
Vec3 point_at(const std::vector<Vec3>& line, const std::vector<double>& cum, double s) {
  if (s <= 0) return line.front();
  if (s >= cum.back()) return line.back();
  const size_t i = std::upper_bound(cum.begin(), cum.end(), s) - cum.begin();
  const double seg = cum[i] - cum[i - 1];
  return lerp(line[i - 1], line[i], seg > 0 ? static_cast<float>((s - cum[i - 1]) / seg) : 0.0f);
}

// A player looks where there is room to look: at each key the heading may turn by up to
// +-`search` degrees (15-degree steps) towards a longer horizontal line of sight. The turns are
// chosen jointly along the path (dynamic programming: long sight lines and small turns are
// rewarded, changing the turn between neighbouring keys costs), so the view does not flicker
// between two openings. Returns the turn per key, degrees.
std::vector<float> open_space_turns(const BspCollision& collision, const std::vector<Vec3>& eyes,
                                    const std::vector<float>& yaw_degrees, float search) {
  const size_t n = eyes.size();
  std::vector<float> candidates;
  for (float t = -std::floor(search / 15) * 15; t <= search + 1e-3f; t += 15) candidates.push_back(t);
  if (candidates.size() <= 1) return std::vector<float>(n, 0.0f);
  const size_t m = candidates.size();
  constexpr float kRange = 2048, kSwitchCost = 0.5f;
  std::vector<float> cost(m), next(m);
  std::vector<std::vector<uint8_t>> from(n, std::vector<uint8_t>(m, 0));
  for (size_t k = 0; k < n; ++k) {
    for (size_t i = 0; i < m; ++i) {
      const float a = (yaw_degrees[k] + candidates[i]) / kDeg;
      const Vec3 ray{std::cos(a) * kRange, std::sin(a) * kRange, 0};
      const float sight = std::clamp(collision.trace(eyes[k], eyes[k] + ray, Vec3{}).fraction * kRange, 8.0f, 1024.0f);
      const float local = -std::log(sight) - std::log(0.5f + 0.5f * std::cos(candidates[i] / kDeg));
      if (k == 0) {
        next[i] = local;
        continue;
      }
      float best = std::numeric_limits<float>::infinity();
      for (size_t j = 0; j < m; ++j) {
        const float c = cost[j] + kSwitchCost * std::fabs(candidates[i] - candidates[j]) / 15.0f;
        if (c < best) best = c, from[k][i] = static_cast<uint8_t>(j);
      }
      next[i] = best + local;
    }
    cost = next;
  }
  std::vector<float> turns(n);
  size_t at = std::min_element(cost.begin(), cost.end()) - cost.begin();
  for (size_t k = n; k-- > 0;) {
    turns[k] = candidates[at];
    at = from[k][at];
  }
  return turns;
}

}  // namespace

std::string CameraPathReport::summary() const {
  std::ostringstream s;
  s << candidates << " spawn points/items, " << waypoints << " usable waypoints (dropped: " << dropped_in_solid
    << " in solid, " << dropped_no_floor << " without floor, " << dropped_outside << " outside, "
    << dropped_in_liquid << " in liquid, " << dropped_near_surface << " touching surfaces, " << dropped_unreachable
    << " unreachable; " << merged << " merged), " << navigation_nodes << " navigation nodes, " << visited
    << " visits, " << softened_spans << " softened and " << straightened_spans
    << " straightened spans, path " << static_cast<int>(length) << " units" << (turntable ? " (turntable)" : "");
  return s.str();
}

QuakeCameraPath build_camera_path(const std::vector<Entity>& entities, const BspCollision& collision,
                                  const SurfaceObstacles& obstacles, const CameraPathOptions& o,
                                  const std::string& context) {
  QuakeCameraPath path;
  CameraPathReport& report = path.report;
  const EyePlacer placer(collision, obstacles, o);
  std::vector<Node> nodes = collect_targets(entities, placer, o, context, report);
  if (nodes.empty()) throw Error(context, "no spawn point or item where a camera fits (" + report.summary() + ")");

  std::mt19937_64 rng(o.seed ^ 0x9E3779B97F4A7C15ull);
  std::vector<int> spawns;
  for (size_t i = 0; i < nodes.size(); ++i)
    if (nodes[i].spawn) spawns.push_back(static_cast<int>(i));
  const std::vector<int> pool = spawns.empty() ? std::vector<int>{0} : spawns;
  const int start = pool[std::uniform_int_distribution<size_t>(0, pool.size() - 1)(rng)];
  const float phase_yaw = std::uniform_real_distribution<float>(0, 2 * kPiF)(rng);
  const float phase_pitch = std::uniform_real_distribution<float>(0, 2 * kPiF)(rng);

  add_navigation_nodes(collision.bsp(), placer, o, nodes, report);
  const Clearance clear(collision, obstacles, o);
  LinkGraph graph(nodes, clear, o);
  const std::vector<int> route = plan_route(nodes, graph, o.length + o.look_ahead, start, report);
  const std::vector<Vec3> eyes = shorten(nodes, route, clear, o.max_link);

  // Dense polyline along the verified spline.
  std::vector<Vec3> line{eyes.front()};
  for (size_t i = 0; i + 1 < eyes.size(); ++i) {
    const CurveSegment full = centripetal_span(eyes, i);
    for (float scale : {1.0f, 0.5f, 0.0f}) {
      const CurveSegment span{full.p0, full.p1, full.m0 * scale, full.m1 * scale};
      const float chord = length(span.p1 - span.p0);
      const int steps = std::max(1, static_cast<int>(std::ceil(chord / o.key_spacing)));
      std::vector<Vec3> samples;
      bool ok = true;
      Vec3 previous = span.p0;
      for (int k = 1; k <= steps && ok; ++k) {
        const Vec3 q = k == steps ? span.p1 : span.at(static_cast<float>(k) / steps);
        ok = scale == 0.0f || clear.segment(previous, q);  // the straight link was verified
        samples.push_back(q);
        previous = q;
      }
      if (!ok) continue;
      if (scale == 0.5f) ++report.softened_spans;
      if (scale == 0.0f) ++report.straightened_spans;
      line.insert(line.end(), samples.begin(), samples.end());
      break;
    }
  }
  std::vector<double> cum{0};
  for (size_t i = 1; i < line.size(); ++i) cum.push_back(cum.back() + length(line[i] - line[i - 1]));

  if (cum.back() < 1.0) {
    // One reachable waypoint: turn on the spot, a full circle.
    report.turntable = true;
    const int keys = 64;
    for (int k = 0; k < keys; ++k) {
      const float t = static_cast<float>(k) / (keys - 1);
      path.keys.push_back({line.front(), 360.0f * t,
                           o.pitch_sway_degrees * std::sin(2 * kPiF * t + phase_pitch), static_cast<double>(k)});
    }
    return path;
  }

  const double total = std::min<double>(o.length, cum.back());
  report.length = static_cast<float>(total);
  const int keys = std::max(2, static_cast<int>(std::ceil(total / o.key_spacing)) + 1);
  const double spacing = total / (keys - 1);
  std::vector<Vec3> positions(keys), looks(keys);
  Vec3 last_direction = line.size() > 1 ? normalize(line[1] - line[0]) : Vec3{1, 0, 0};
  for (int k = 0; k < keys; ++k) {
    positions[k] = point_at(line, cum, k * spacing);
    const Vec3 ahead = point_at(line, cum, k * spacing + o.look_ahead) - positions[k];
    if (length(ahead) >= 1.0f) last_direction = normalize(ahead);
    looks[k] = last_direction;
  }
  // Heading: the look directions averaged over +-look_ahead (Gaussian), so corners are anticipated
  // and left gradually.
  const int radius = std::max(1, static_cast<int>(std::lround(o.look_ahead / spacing)));
  std::vector<float> weights(2 * radius + 1);
  for (int j = -radius; j <= radius; ++j) weights[j + radius] = std::exp(-2.0f * j * j / float(radius * radius));
  std::vector<float> heading_yaw(keys), heading_pitch(keys);
  for (int k = 0; k < keys; ++k) {
    Vec3 heading{};
    for (int j = -radius; j <= radius; ++j) heading += looks[std::clamp(k + j, 0, keys - 1)] * weights[j + radius];
    if (length(heading) < 1e-3f) heading = looks[k];
    heading_yaw[k] = std::atan2(heading.y, heading.x) * kDeg;
    heading_pitch[k] = std::atan2(heading.z, std::hypot(heading.x, heading.y)) * kDeg;
  }
  // Turned towards open space, coherently along the path, then smoothed like the heading.
  const std::vector<float> turns = open_space_turns(collision, positions, heading_yaw, o.open_space_degrees);
  // Turn-rate limits, degrees per key: a reversal (a dead end) becomes a turn, not a jump.
  const float max_yaw_step = o.max_turn_rate * static_cast<float>(spacing);
  const float max_pitch_step = 0.5f * max_yaw_step;
  float yaw = 0, pitch = 0;
  for (int k = 0; k < keys; ++k) {
    float turn = 0, weight = 0;
    for (int j = -radius; j <= radius; ++j) {
      turn += turns[std::clamp(k + j, 0, keys - 1)] * weights[j + radius];
      weight += weights[j + radius];
    }
    const float target_yaw = heading_yaw[k] + turn / weight, target_pitch = heading_pitch[k];
    if (k == 0) {
      yaw = target_yaw;
      pitch = target_pitch;
    } else {
      yaw += std::clamp(wrap180(target_yaw - yaw), -max_yaw_step, max_yaw_step);  // continuous
      pitch += std::clamp(target_pitch - pitch, -max_pitch_step, max_pitch_step);
    }
    const float s = static_cast<float>(k * spacing);
    QuakeCameraKey key;
    key.position = positions[k];
    key.distance = k * spacing;
    key.yaw = yaw + o.yaw_sway_degrees * std::sin(2 * kPiF * s / o.yaw_sway_period + phase_yaw);
    key.pitch = std::clamp(pitch + o.pitch_sway_degrees * std::sin(2 * kPiF * s / o.pitch_sway_period + phase_pitch),
                           -o.max_pitch, o.max_pitch);
    path.keys.push_back(key);
  }
  return path;
}

}  // namespace cgsr::q3
