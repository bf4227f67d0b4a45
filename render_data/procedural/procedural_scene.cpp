#include "render_data/procedural/procedural_scene.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <tuple>

#include <spdlog/spdlog.h>

#include "core/error.h"
#include "render_data/procedural/mesh_builder.h"
#include "render_data/procedural/procedural_rng.h"
#include "render_data/procedural/procedural_textures.h"
#include "render_data/procedural/procedural_variety.h"
#include "render_data/scene_source.h"
#include "render_data/vec_math.h"

namespace cgsr {
namespace {


using Rng = ProceduralRng;

Vec3 vec3(const std::vector<float>& v) { return {v[0], v[1], v[2]}; }

enum CellKind : uint8_t { Free = 0, Wall = 1, Occupied = 2, Path = 3 };
const int kDx[4] = {1, 0, -1, 0}, kDz[4] = {0, 1, 0, -1};

struct Grid {
  int nx = 0, nz = 0;
  float cell = 1;
  std::vector<uint8_t> kind;
  std::vector<float> height;  // per wall cell: its own height (outdoor buildings); 0: the level's wall height
  bool inside(int x, int z) const { return x >= 0 && z >= 0 && x < nx && z < nz; }
  uint8_t& at(int x, int z) { return kind[static_cast<size_t>(z) * nx + x]; }
  uint8_t get(int x, int z) const { return inside(x, z) ? kind[static_cast<size_t>(z) * nx + x] : static_cast<uint8_t>(Wall); }
  Vec3 centre(int x, int z, float y = 0) const { return {(x + 0.5f) * cell, y, (z + 0.5f) * cell}; }
};

class LevelBuilder {
 public:
  LevelBuilder(const ProceduralOptions& o, uint64_t seed) : o_(o), rng_(seed) {
    grid_.nx = o.size[0];
    grid_.nz = o.size[1];
    grid_.cell = o.cell;
    grid_.kind.assign(static_cast<size_t>(grid_.nx) * grid_.nz, Free);
    grid_.height.assign(grid_.kind.size(), 0.0f);
    arena_ = o.layout == ProceduralLayout::Arena;
    hall_ = o.layout == ProceduralLayout::Hall;
    outdoor_ = o.layout == ProceduralLayout::Outdoor;
    open_sky_ = arena_ || outdoor_;
    variety_ = o.variety.enabled;
    ceiling_ = o.ceiling && !open_sky_;
    wall_height_ = arena_ ? std::min(o.height, 1.4f) : o.height;
    uv_ = o.texel_density / static_cast<float>(o.texture_size);
  }

  SceneBundle build() {
    scene_.name = o_.name;
    switch (o_.layout) {
      case ProceduralLayout::Room: layout_room(); break;
      case ProceduralLayout::Corridors: layout_corridors(); break;
      case ProceduralLayout::Hall: layout_hall(); break;
      case ProceduralLayout::Outdoor: layout_outdoor(); break;
      case ProceduralLayout::Arena: layout_arena(); break;
      case ProceduralLayout::Random:
        throw Error("procedural scene '" + o_.name + "'", "layout random reached the builder undrawn", ErrorKind::Internal);
    }
    build_structure();
    const auto walk = camera_walk();
    for (const auto& [x, z] : walk) grid_.at(x, z) = Path;
    add_lights();
    add_props();
    scene_.sky.horizon = vec3(o_.sky_horizon);
    scene_.sky.zenith = vec3(o_.sky_zenith);
    scene_.fog.density = o_.fog.density;
    scene_.fog.start = o_.fog.start;
    scene_.fog.color = vec3(o_.fog.color);
    scene_.ambient = Vec3{1, 1, 1} * o_.lighting.ambient;
    SceneBundle out;
    out.scene = std::move(scene_);
    out.camera = camera_path(walk);
    return out;
  }

 private:
  // ---- materials -------------------------------------------------------------------------------
  int material(TextureKind kind, Vec3 base, Vec3 accent, float specular, float shininess, float alpha_cutoff = 0) {
    Texture t = make_texture(kind, o_.texture_size, rng_.bits(), base, accent);
    scene_.textures.push_back(std::move(t));
    Material m;
    m.name = texture_kind_names()[static_cast<size_t>(kind)] + std::to_string(scene_.materials.size());
    m.albedo_texture = static_cast<int>(scene_.textures.size() - 1);
    m.specular = specular;
    m.shininess = shininess;
    m.alpha_cutoff = alpha_cutoff;
    scene_.materials.push_back(m);
    return static_cast<int>(scene_.materials.size() - 1);
  }
  int flat_material(Vec3 tint, float specular, float shininess, bool unlit = false) {
    Material m;
    m.name = "flat" + std::to_string(scene_.materials.size());
    m.tint = tint;
    m.specular = specular;
    m.shininess = shininess;
    m.unlit = unlit;
    scene_.materials.push_back(m);
    return static_cast<int>(scene_.materials.size() - 1);
  }
  Vec3 pick_colour(const std::vector<Vec3>& palette) { return rng_.pick(palette); }
  // Variety: a texture family without holes, random colours and gloss.
  int family_material() {
    std::vector<TextureKind> solid;
    for (const auto& name : o_.variety.materials)
      if (!texture_kind_has_holes(texture_kind_from_name(name))) solid.push_back(texture_kind_from_name(name));
    const TextureKind kind = rng_.pick(solid);
    Vec3 base, accent;
    random_albedo(rng_, base, accent);
    const float specular = rng_.chance(0.3) ? rng_.range(0.3f, 0.8f) : rng_.range(0.0f, 0.2f);
    return material(kind, base, accent, specular, rng_.range(8.0f, 96.0f));
  }

  int wall_material() {
    if (wall_mat_ < 0 && variety_) wall_mat_ = family_material();
    if (wall_mat_ < 0) {
      const TextureKind kind = rng_.pick(std::vector<TextureKind>{TextureKind::Bricks, TextureKind::Bricks,
                                                                   TextureKind::Plates, TextureKind::Noise});
      wall_mat_ = material(kind, pick_colour({{0.55f, 0.3f, 0.22f}, {0.62f, 0.55f, 0.45f}, {0.45f, 0.47f, 0.52f}}),
                           {0.72f, 0.7f, 0.64f}, 0.05f, 16);
    }
    return wall_mat_;
  }
  int metal_material() {
    if (metal_mat_ < 0) metal_mat_ = flat_material({0.35f, 0.36f, 0.38f}, 0.6f, 64);
    return metal_mat_;
  }
  int object() { return next_object_++; }
  void add(MeshBuilder& b) {
    if (!b.empty()) scene_.meshes.push_back(b.finish());
  }

  // ---- layouts -----------------------------------------------------------------------------------
  void border_walls() {
    for (int x = 0; x < grid_.nx; ++x) grid_.at(x, 0) = grid_.at(x, grid_.nz - 1) = Wall;
    for (int z = 0; z < grid_.nz; ++z) grid_.at(0, z) = grid_.at(grid_.nx - 1, z) = Wall;
  }
  void layout_room() {
    border_walls();
    // A partition with a doorway in larger rooms.
    if (grid_.nx >= 8 && grid_.nz >= 6) {
      const int x = grid_.nx / 2 + rng_.below(3) - 1;
      const int door = 1 + rng_.below(grid_.nz - 4);
      for (int z = 1; z < grid_.nz - 1; ++z)
        if (z != door && z != door + 1) grid_.at(x, z) = Wall;
    }
  }
  void layout_corridors() {
    // A maze on the odd cells (randomized depth-first search), then a few extra openings (loops)
    // and one small hall so props have space off the camera's walk.
    std::fill(grid_.kind.begin(), grid_.kind.end(), Wall);
    std::vector<std::pair<int, int>> stack{{1, 1}};
    grid_.at(1, 1) = Free;
    while (!stack.empty()) {
      const auto [x, z] = stack.back();
      std::vector<int> dirs;
      for (int d = 0; d < 4; ++d) {
        const int nx = x + 2 * kDx[d], nz = z + 2 * kDz[d];
        if (nx > 0 && nz > 0 && nx < grid_.nx - 1 && nz < grid_.nz - 1 && grid_.at(nx, nz) == Wall) dirs.push_back(d);
      }
      if (dirs.empty()) {
        stack.pop_back();
        continue;
      }
      const int d = rng_.pick(dirs);
      grid_.at(x + kDx[d], z + kDz[d]) = Free;
      grid_.at(x + 2 * kDx[d], z + 2 * kDz[d]) = Free;
      stack.push_back({x + 2 * kDx[d], z + 2 * kDz[d]});
    }
    for (int z = 1; z < grid_.nz - 1; ++z)
      for (int x = 1; x < grid_.nx - 1; ++x)
        if (grid_.at(x, z) == Wall && rng_.chance(0.12)) {
          const bool between_x = grid_.get(x - 1, z) != Wall && grid_.get(x + 1, z) != Wall;
          const bool between_z = grid_.get(x, z - 1) != Wall && grid_.get(x, z + 1) != Wall;
          if (between_x != between_z) grid_.at(x, z) = Free;
        }
    if (grid_.nx >= 7 && grid_.nz >= 7) {
      const int hx = 1 + rng_.below(grid_.nx - 5), hz = 1 + rng_.below(grid_.nz - 5);
      for (int z = hz; z < hz + 3; ++z)
        for (int x = hx; x < hx + 3; ++x) grid_.at(x, z) = Free;
    }
  }
  void layout_arena() {
    border_walls();
    // Raised blocks (cover) scattered over the field.
    const int blocks = grid_.nx * grid_.nz / 25;
    for (int i = 0; i < blocks; ++i) {
      const int x = 2 + rng_.below(std::max(1, grid_.nx - 4)), z = 2 + rng_.below(std::max(1, grid_.nz - 4));
      if (grid_.inside(x, z)) grid_.at(x, z) = Wall;
    }
  }
  void layout_hall() {
    // One large high room with a colonnade: columns in every third cell, two cells from the
    // walls. Column cells count as walls for the camera walk and are built as round columns.
    border_walls();
    const int offset = 2 + rng_.below(2);
    for (int z = offset; z < grid_.nz - 2; z += 3)
      for (int x = offset; x < grid_.nx - 2; x += 3) {
        grid_.at(x, z) = Wall;
        columns_.insert(z * grid_.nx + x);
      }
  }
  void layout_outdoor() {
    // Open ground under the sky with buildings of different heights (blocks of 1-3 x 1-2 cells);
    // the camera walks the streets between them. No boundary wall: the grid's edge stops the walk.
    const int buildings = std::max(1, grid_.nx * grid_.nz / 14);
    for (int i = 0; i < buildings; ++i) {
      const bool wide = rng_.chance(0.5);
      const int w = wide ? rng_.between(1, 3) : rng_.between(1, 2), d = wide ? rng_.between(1, 2) : rng_.between(1, 3);
      const int x0 = rng_.below(std::max(1, grid_.nx - w)), z0 = rng_.below(std::max(1, grid_.nz - d));
      const float h = rng_.range(3.0f, 10.0f);
      for (int z = z0; z < std::min(grid_.nz, z0 + d); ++z)
        for (int x = x0; x < std::min(grid_.nx, x0 + w); ++x) {
          grid_.at(x, z) = Wall;
          grid_.height[static_cast<size_t>(z) * grid_.nx + x] = h;
        }
    }
  }
  bool is_column(int x, int z) const { return columns_.count(z * grid_.nx + x) > 0; }

  // ---- walls, floor, ceiling ------------------------------------------------------------------------
  void build_structure() {
    const float c = grid_.cell, W = grid_.nx * c, D = grid_.nz * c;
    // Walls: runs of wall cells (of one height) along x merged into one box each. With variety,
    // runs and buildings take one of up to three wall materials.
    std::vector<MeshBuilder> walls{MeshBuilder("walls", wall_material(), object())};
    for (int extra = variety_ ? rng_.below(3) : 0; extra > 0; --extra)
      walls.emplace_back("walls", family_material(), object());
    auto cell_height = [&](int x, int z) { return grid_.height[static_cast<size_t>(z) * grid_.nx + x]; };
    auto is_wall = [&](int x, int z) { return grid_.at(x, z) == Wall && !is_column(x, z); };
    for (int z = 0; z < grid_.nz; ++z)
      for (int x = 0; x < grid_.nx;) {
        if (!is_wall(x, z)) {
          ++x;
          continue;
        }
        int end = x;
        while (end < grid_.nx && is_wall(end, z) && cell_height(end, z) == cell_height(x, z)) ++end;
        // Interior blocks of an arena are lower than its boundary.
        const bool boundary = z == 0 || z == grid_.nz - 1 || x == 0 || end == grid_.nx;
        const float h = cell_height(x, z) > 0 ? cell_height(x, z) : arena_ && !boundary ? 0.9f : wall_height_;
        // A building keeps one material on all its rows (its height tells it apart).
        const size_t which = walls.size() == 1       ? 0
                             : cell_height(x, z) > 0 ? static_cast<size_t>(h * 7) % walls.size()
                                                     : static_cast<size_t>(rng_.below(static_cast<int>(walls.size())));
        walls[which].box({x * c, 0, z * c}, {end * c, h, (z + 1) * c}, uv_);
        x = end;
      }
    for (auto& w : walls) add(w);
    if (!columns_.empty()) build_columns();
    if (outdoor_) build_skyline();

    int floor_mat;
    if (variety_) {
      floor_mat = family_material();
    } else {
      const TextureKind floor_kind =
          rng_.pick(std::vector<TextureKind>{TextureKind::Tiles, TextureKind::Checker, TextureKind::Planks});
      floor_mat = material(floor_kind, pick_colour({{0.6f, 0.58f, 0.52f}, {0.42f, 0.3f, 0.2f}, {0.5f, 0.52f, 0.55f}}),
                           {0.25f, 0.24f, 0.22f}, 0.15f, 32);
    }
    MeshBuilder floor("floor", floor_mat, object());
    // Under the sky the ground continues beyond the level to the horizon.
    const float margin = open_sky_ ? 4 * std::max(W, D) : 0;
    floor.quad({-margin, 0, D + margin}, {W + 2 * margin, 0, 0}, {0, 0, -(D + 2 * margin)}, uv_);
    add(floor);
    if (ceiling_) {
      const int ceil_mat = variety_ ? family_material()
                                    : material(rng_.chance(0.5) ? TextureKind::Plates : TextureKind::Noise,
                                               {0.55f, 0.55f, 0.56f}, {0.3f, 0.3f, 0.32f}, 0.05f, 16);
      MeshBuilder ceiling("ceiling", ceil_mat, object());
      ceiling.quad({0, wall_height_, 0}, {W, 0, 0}, {0, 0, D}, uv_);
      add(ceiling);
    }
    if (hall_ && wall_height_ >= 6.0f) build_gallery();
  }

  // Hall columns: a round shaft on a square base under a square capital, floor to ceiling.
  void build_columns() {
    const int mat = variety_ ? family_material() : wall_material();
    const float r = 0.22f * grid_.cell, h = wall_height_;
    for (int key : columns_) {
      const int x = key % grid_.nx, z = key / grid_.nx;
      MeshBuilder b("column", mat, object());
      const Vec3 foot = grid_.centre(x, z), pad{r + 0.15f, 0, r + 0.15f};
      b.box(foot - pad, grid_.centre(x, z, 0.4f) + pad, uv_);
      b.cylinder(grid_.centre(x, z, 0.4f), {0, h - 0.8f, 0}, r, 24, uv_);
      b.box(grid_.centre(x, z, h - 0.4f) - pad, grid_.centre(x, z, h) + pad, uv_);
      add(b);
    }
  }

  // A hall's gallery: a slab along the first wall, well above the camera, with a railing.
  void build_gallery() {
    const float c = grid_.cell, y = wall_height_ * 0.5f, depth = std::min(1.5f, 0.6f * c);
    MeshBuilder slab("gallery", wall_material(), object());
    slab.box({c, y - 0.3f, c}, {(grid_.nx - 1) * c, y, c + depth}, uv_);
    add(slab);
    add_railing_between({c, y, c + depth - 0.05f}, {(grid_.nx - 1) * c, y, c + depth - 0.05f});
  }

  // Outdoors: tall blocks beyond the level's edge, a skyline for the long views.
  void build_skyline() {
    const float c = grid_.cell, W = grid_.nx * c, D = grid_.nz * c;
    MeshBuilder b("skyline", wall_material(), object());
    for (int i = 0; i < 16; ++i) {
      const int side = i % 4;
      const float along = rng_.range(-0.2f, 1.2f), away = rng_.range(2.0f, 8.0f) * c;
      const float w = rng_.range(1.5f, 4.0f) * c, d = rng_.range(1.5f, 4.0f) * c, h = rng_.range(8.0f, 30.0f);
      const Vec3 centre = side == 0   ? Vec3{along * W, 0, -away - d / 2}
                          : side == 1 ? Vec3{along * W, 0, D + away + d / 2}
                          : side == 2 ? Vec3{-away - w / 2, 0, along * D}
                                      : Vec3{W + away + w / 2, 0, along * D};
      b.box(centre - Vec3{w / 2, 0, d / 2}, centre + Vec3{w / 2, h, d / 2}, uv_);
    }
    add(b);
  }

  // ---- camera ---------------------------------------------------------------------------------------
  std::vector<std::pair<int, int>> camera_walk() {
    std::vector<std::pair<int, int>> free;
    for (int z = 0; z < grid_.nz; ++z)
      for (int x = 0; x < grid_.nx; ++x)
        if (grid_.at(x, z) == Free) free.push_back({x, z});
    if (free.empty()) throw Error("procedural scene '" + o_.name + "'", "the layout has no free cell for the camera");
    int x, z;
    // Start in a cell with room around it when there is one.
    std::tie(x, z) = free[rng_.below(static_cast<int>(free.size()))];
    for (int tries = 0; tries < 50; ++tries) {
      const auto cand = free[rng_.below(static_cast<int>(free.size()))];
      int open = 0;
      for (int d = 0; d < 4; ++d) open += grid_.get(cand.first + kDx[d], cand.second + kDz[d]) == Free;
      if (open >= 3) {
        std::tie(x, z) = cand;
        break;
      }
    }
    std::vector<std::pair<int, int>> walk{{x, z}};
    int dir = rng_.below(4);
    for (int step = 1; step < std::max(2, o_.camera.steps); ++step) {
      auto recent = [&](int cx, int cz) {
        for (size_t k = walk.size() > 8 ? walk.size() - 8 : 0; k < walk.size(); ++k)
          if (walk[k].first == cx && walk[k].second == cz) return true;
        return false;
      };
      auto open = [&](int d) { return grid_.get(x + kDx[d], z + kDz[d]) != Wall; };
      std::vector<int> fresh, any;
      for (int d = 0; d < 4; ++d)
        if (open(d)) {
          any.push_back(d);
          if (!recent(x + kDx[d], z + kDz[d])) fresh.push_back(d);
        }
      if (any.empty()) break;  // a single enclosed cell
      const bool keep = std::find(fresh.begin(), fresh.end(), dir) != fresh.end() && rng_.chance(0.6);
      if (!keep) dir = fresh.empty() ? rng_.pick(any) : rng_.pick(fresh);
      x += kDx[dir];
      z += kDz[dir];
      walk.push_back({x, z});
    }
    return walk;
  }

  CameraPath camera_path(const std::vector<std::pair<int, int>>& walk) {
    const auto& cam = o_.camera;
    CameraPath path;
    path.near_plane = cam.near_plane;
    path.far_plane = cam.far_plane;
    const float phase_yaw = rng_.range(0, 2 * kPiF), phase_pitch = rng_.range(0, 2 * kPiF), phase_roll = rng_.range(0, 2 * kPiF);
    std::vector<Vec3> points;
    for (const auto& [x, z] : walk) {
      const float j = 0.12f * grid_.cell;
      points.push_back(grid_.centre(x, z, cam.eye_height + rng_.range(-0.08f, 0.08f)) + Vec3{rng_.range(-j, j), 0, rng_.range(-j, j)});
    }
    if (points.size() == 1) points.push_back(points[0] + Vec3{0.01f, 0, 0});  // a turn on the spot
    double time = 0;
    float previous_yaw = 0;
    for (size_t k = 0; k < points.size(); ++k) {
      const Vec3 ahead = points[std::min(k + 1, points.size() - 1)] - points[k > 0 ? k - 1 : 0];
      float heading = std::atan2(-ahead.x, -ahead.z) * 180.0f / kPiF;  // yaw that looks along `ahead`
      if (k > 0) {  // unwrap: the path's yaw values are continuous
        while (heading - previous_yaw > 180) heading -= 360;
        while (heading - previous_yaw < -180) heading += 360;
      }
      previous_yaw = heading;
      CameraKey key;
      key.pose.position = points[k];
      key.pose.yaw = heading + cam.yaw_sway * std::sin(0.9f * k + phase_yaw) * rng_.range(0.5f, 1.0f);
      key.pose.pitch = cam.pitch_sway * std::sin(0.7f * k + phase_pitch);
      key.pose.roll = cam.roll * std::sin(0.5f * k + phase_roll);
      key.pose.vfov = cam.vfov;
      if (k > 0) {
        const float speed = 1.0f + cam.speed_variation * rng_.range(-1.0f, 1.0f);
        time += std::max(0.05f, length(points[k] - points[k - 1])) / std::max(0.1f, speed);
      }
      key.time = time;
      path.keys.push_back(key);
    }
    return path;
  }

  // ---- lights ---------------------------------------------------------------------------------------
  void add_lights() {
    const auto& L = o_.lighting;
    if (L.sun || open_sky_) {
      Light sun;
      sun.type = LightType::Directional;
      sun.direction = normalize(Vec3{rng_.range(-0.6f, 0.6f), -1.0f, rng_.range(-0.6f, 0.6f)});
      sun.color = {1.0f, 0.95f, 0.85f};
      sun.intensity = L.sun_intensity;
      sun.shadows = L.shadows;
      scene_.lights.push_back(sun);
    }
    std::vector<std::pair<int, int>> cells;
    for (int z = 0; z < grid_.nz; ++z)
      for (int x = 0; x < grid_.nx; ++x)
        if (grid_.at(x, z) == Free || (!open_sky_ && grid_.at(x, z) == Path)) cells.push_back({x, z});
    const int lamp_mat = flat_material({1.0f, 0.92f, 0.75f}, 0, 1, /*unlit=*/true);
    for (int i = 0; i < L.point_lights && !cells.empty(); ++i) {
      const int k = rng_.below(static_cast<int>(cells.size()));
      const auto [x, z] = cells[k];
      cells.erase(cells.begin() + k);
      Light light;
      light.type = LightType::Point;
      // Hall lamps hang from cables at most 5 m above the floor.
      const float y = open_sky_ ? 3.6f : hall_ ? std::min(wall_height_ - 0.45f, 5.0f) : wall_height_ - 0.45f;
      light.position = grid_.centre(x, z, y);
      if (variety_ && rng_.chance(o_.variety.coloured_lights)) {
        const float hue = rng_.range(0, 1);
        light.color = hsv_colour(hue, rng_.range(0.45f, 0.85f), 1.0f);
      } else {
        light.color = rng_.pick(std::vector<Vec3>{{1.0f, 0.85f, 0.65f}, {0.75f, 0.85f, 1.0f}, {1.0f, 0.95f, 0.9f}});
      }
      light.intensity = L.point_intensity;
      light.radius = 2.0f * grid_.cell;
      light.shadows = L.shadows;
      scene_.lights.push_back(light);
      MeshBuilder lamp("lamp", lamp_mat, object());
      lamp.box(light.position + Vec3{-0.15f, 0.12f, -0.15f}, light.position + Vec3{0.15f, 0.25f, 0.15f}, 1.0f);
      add(lamp);
      if (hall_ && y + 0.25f < wall_height_) {
        MeshBuilder cable("wire", metal_material(), object());
        cable.tube({light.position + Vec3{0, 0.25f, 0}, grid_.centre(x, z, wall_height_)}, 0.012f, 6, 1.0f);
        add(cable);
      }
      if (open_sky_) {  // lamp post (cells with posts become obstacles)
        MeshBuilder post("lamp post", metal_material(), object());
        post.cylinder(grid_.centre(x, z), {0, y + 0.1f, 0}, 0.06f, 10, 1.0f);
        add(post);
        grid_.at(x, z) = Occupied;
      }
    }
  }

  // ---- props ----------------------------------------------------------------------------------------
  // A free cell off the camera path (and a free neighbour, with its direction); when there is none,
  // the prop is counted as skipped (an error at the end) unless `may_skip`.
  bool take_cell(int& x, int& z, bool need_free_neighbour = false, int* dir_out = nullptr, bool may_skip = false) {
    std::vector<std::pair<int, int>> cells;
    for (int cz = 0; cz < grid_.nz; ++cz)
      for (int cx = 0; cx < grid_.nx; ++cx)
        if (grid_.at(cx, cz) == Free) cells.push_back({cx, cz});
    while (!cells.empty()) {
      const int k = rng_.below(static_cast<int>(cells.size()));
      std::tie(x, z) = cells[k];
      cells.erase(cells.begin() + k);
      if (!need_free_neighbour) {
        grid_.at(x, z) = Occupied;
        return true;
      }
      std::vector<int> dirs;
      for (int d = 0; d < 4; ++d)
        if (grid_.get(x + kDx[d], z + kDz[d]) == Free) dirs.push_back(d);
      if (dirs.empty()) continue;
      *dir_out = rng_.pick(dirs);
      grid_.at(x, z) = Occupied;
      grid_.at(x + kDx[*dir_out], z + kDz[*dir_out]) = Occupied;
      return true;
    }
    if (!may_skip) ++skipped_props_;
    return false;
  }

  // Variety: scales the props that need cells down until they take at most half of the free
  // cells (a random size and layout may be much smaller than what the counts were made for);
  // stairs, which need two free neighbouring cells, go first and only where such a pair is left.
  void fit_props(ProceduralProps& p) const {
    int free = 0;
    for (uint8_t k : grid_.kind) free += k == Free;
    int* counts[] = {&p.crates, &p.pillars, &p.spheres, &p.tori, &p.stairs, &p.fences, &p.railings, &p.grates};
    int demand = p.stairs;  // stairs take two cells
    for (int* n : counts) demand += *n;
    if (demand <= free / 2) return;
    const double factor = static_cast<double>(free / 2) / demand;
    for (int* n : counts) *n = static_cast<int>(*n * factor);
  }

  void place_stairs(int count, bool may_skip) {
    int x, z;
    for (int i = 0; i < count; ++i) {
      int dir = 0;
      if (!take_cell(x, z, true, &dir, may_skip)) break;
      add_stairs(x, z, dir);
    }
  }

  void add_props() {
    ProceduralProps p = o_.props;
    if (variety_) {
      fit_props(p);
      place_stairs(p.stairs, /*may_skip=*/true);  // first, while pairs of free cells are easy to find
    }
    const float c = grid_.cell;
    int x, z;
    if (p.crates > 0) {
      const int mat = variety_ ? family_material()
                               : material(rng_.chance(0.6) ? TextureKind::Planks : TextureKind::Stripes,
                                          {0.62f, 0.45f, 0.25f}, {0.2f, 0.14f, 0.08f}, 0.05f, 16);
      for (int i = 0; i < p.crates && take_cell(x, z); ++i) {
        MeshBuilder b("crate", mat, object());
        float s = rng_.range(0.5f, 0.95f), y = 0;
        for (int level = 0; level < (rng_.chance(0.35) ? 2 : 1); ++level) {
          const float yaw = rng_.range(0, kPiF / 2);
          const Vec3 ax{std::cos(yaw), 0, -std::sin(yaw)}, az{std::sin(yaw), 0, std::cos(yaw)};
          b.oriented_box(grid_.centre(x, z, y + s / 2) + Vec3{rng_.range(-0.1f, 0.1f) * c, 0, rng_.range(-0.1f, 0.1f) * c},
                         ax, {0, 1, 0}, az, {s / 2, s / 2, s / 2}, 1.0f / s);
          y += s;
          s *= 0.7f;
        }
        add(b);
      }
    }
    if (p.pillars > 0) {
      const int mat = variety_ ? family_material()
                               : material(rng_.chance(0.5) ? TextureKind::Noise : TextureKind::Bricks, {0.7f, 0.68f, 0.62f},
                                          {0.45f, 0.43f, 0.4f}, 0.2f, 32);
      const float h = ceiling_ ? wall_height_ : 4.5f;
      for (int i = 0; i < p.pillars && take_cell(x, z); ++i) {
        MeshBuilder b("pillar", mat, object());
        const float r = rng_.range(0.22f, 0.34f);
        b.box(grid_.centre(x, z) - Vec3{r + 0.1f, 0, r + 0.1f}, grid_.centre(x, z, 0.3f) + Vec3{r + 0.1f, 0, r + 0.1f}, uv_);
        b.cylinder(grid_.centre(x, z, 0.3f), {0, h - 0.6f, 0}, r, 20, uv_);
        b.box(grid_.centre(x, z, h - 0.3f) - Vec3{r + 0.1f, 0, r + 0.1f}, grid_.centre(x, z, h) + Vec3{r + 0.1f, 0, r + 0.1f}, uv_);
        add(b);
      }
    }
    if (p.spheres > 0) {
      const int mat = variety_ ? family_material()
                               : material(TextureKind::Checker,
                                          pick_colour({{0.8f, 0.2f, 0.15f}, {0.15f, 0.35f, 0.8f}, {0.9f, 0.75f, 0.2f}}),
                                          {0.9f, 0.9f, 0.88f}, 0.5f, 64);
      for (int i = 0; i < p.spheres && take_cell(x, z); ++i) {
        const float r = rng_.range(0.25f, 0.45f);
        float y = 1.3f;
        if (rng_.chance(0.7)) {  // on a pedestal
          MeshBuilder stand("pedestal", wall_material(), object());
          stand.box(grid_.centre(x, z) - Vec3{0.3f, 0, 0.3f}, grid_.centre(x, z, 0.7f) + Vec3{0.3f, 0, 0.3f}, uv_);
          add(stand);
          y = 0.7f + r;
        }
        MeshBuilder b("sphere", mat, object());
        b.sphere(grid_.centre(x, z, y), r, 16, 28, 2.0f);
        add(b);
      }
    }
    if (p.tori > 0) {
      const int mat = variety_ ? family_material()
                               : material(TextureKind::Stripes, {0.85f, 0.7f, 0.1f}, {0.1f, 0.1f, 0.1f}, 0.7f, 96);
      for (int i = 0; i < p.tori && take_cell(x, z); ++i) {
        const float major = rng_.range(0.4f, 0.6f), minor = rng_.range(0.07f, 0.13f);
        const float yaw = rng_.range(0, kPiF);
        MeshBuilder b("torus", mat, object());
        if (rng_.chance(0.6)) b.torus(grid_.centre(x, z, major + minor), {std::cos(yaw), 0, std::sin(yaw)}, major, minor, 40, 14, 1.0f);
        else b.torus(grid_.centre(x, z, 1.2f), {0.2f, 1, 0.1f}, major, minor, 40, 14, 1.0f);
        add(b);
      }
    }
    if (!variety_) place_stairs(p.stairs, /*may_skip=*/false);
    for (int i = 0; i < p.fences && take_cell(x, z); ++i) add_fence(x, z, rng_.below(4));
    for (int i = 0; i < p.railings && take_cell(x, z); ++i) add_railing(x, z, rng_.below(4), 0.0f);
    for (int i = 0; i < p.signs; ++i) add_sign();
    for (int i = 0; i < p.wires; ++i) add_wire();
    for (int i = 0; i < p.grates && take_cell(x, z); ++i) add_grate(x, z, rng_.below(4));
    if (skipped_props_ > 0)
      throw Error("procedural scene '" + o_.name + "'",
                  std::to_string(skipped_props_) + " prop(s) did not fit: the level has too few free cells off the "
                  "camera path (use a larger size or fewer props)");
  }

  // Edge `dir` of cell (x, z): its two end points on the floor.
  void cell_edge(int x, int z, int dir, Vec3& a, Vec3& b) const {
    const float c = grid_.cell;
    const Vec3 o{x * c, 0, z * c};
    switch (dir) {
      case 0: a = o + Vec3{c, 0, 0}, b = o + Vec3{c, 0, c}; break;
      case 1: a = o + Vec3{c, 0, c}, b = o + Vec3{0, 0, c}; break;
      case 2: a = o + Vec3{0, 0, c}, b = o; break;
      default: a = o, b = o + Vec3{c, 0, 0}; break;
    }
  }

  void add_stairs(int x, int z, int dir) {
    // Steps rise across cell (x, z) towards its neighbour in `dir`, which holds the landing.
    const float c = grid_.cell, rise = 0.2f;
    const int steps = 5;
    const Vec3 forward{static_cast<float>(kDx[dir]), 0, static_cast<float>(kDz[dir])};
    const Vec3 side{-forward.z, 0, forward.x};
    const Vec3 start = grid_.centre(x, z) - forward * (c / 2);
    const int id = object();
    MeshBuilder b("stairs", wall_material(), id);
    for (int s = 0; s < steps; ++s) {
      const Vec3 centre = start + forward * ((s + 0.5f) * c / steps) + Vec3{0, (s + 1) * rise / 2, 0};
      b.oriented_box(centre, forward, {0, 1, 0}, side, {c / steps / 2, (s + 1) * rise / 2, c * 0.4f}, uv_);
    }
    const Vec3 landing = grid_.centre(x + kDx[dir], z + kDz[dir], steps * rise / 2);
    b.oriented_box(landing, forward, {0, 1, 0}, side, {c / 2, steps * rise / 2, c * 0.4f}, uv_);
    add(b);
    // Railings on both sides of the landing.
    for (int sgn : {-1, 1}) {
      const Vec3 a = landing + side * (sgn * c * 0.38f) - forward * (c / 2) + Vec3{0, steps * rise / 2, 0};
      add_railing_between(a, a + forward * c);
    }
  }

  void add_railing_between(Vec3 a, Vec3 b) {
    // Thin posts every ~0.25 m with a top rail and a mid rail: the aliasing stress case.
    MeshBuilder r("railing", metal_material(), object());
    const float len = length(b - a);
    const int posts = std::max(2, static_cast<int>(len / 0.25f) + 1);
    for (int i = 0; i < posts; ++i) {
      const Vec3 p = lerp(a, b, static_cast<float>(i) / (posts - 1));
      r.box(p - Vec3{0.015f, 0, 0.015f}, p + Vec3{0.015f, 1.0f, 0.015f}, 1.0f);
    }
    r.tube({a + Vec3{0, 1.0f, 0}, b + Vec3{0, 1.0f, 0}}, 0.025f, 8, 1.0f);
    r.tube({a + Vec3{0, 0.5f, 0}, b + Vec3{0, 0.5f, 0}}, 0.012f, 6, 1.0f);
    add(r);
  }

  void add_railing(int x, int z, int dir, float y) {
    Vec3 a, b;
    cell_edge(x, z, dir, a, b);
    // Pull the railing slightly into its own cell so it never overlaps a wall face.
    const Vec3 inward = (grid_.centre(x, z) - (a + b) * 0.5f) * 0.08f;
    add_railing_between(a + inward + Vec3{0, y, 0}, b + inward + Vec3{0, y, 0});
  }

  void add_fence(int x, int z, int dir) {
    if (fence_mat_ < 0) fence_mat_ = material(TextureKind::ChainLink, {0.7f, 0.72f, 0.75f}, {0, 0, 0}, 0.4f, 48, 0.5f);
    add_panel(x, z, dir, fence_mat_, "fence");
  }

  void add_grate(int x, int z, int dir) {
    if (grate_mat_ < 0) {
      Vec3 base{0.45f, 0.46f, 0.48f}, accent{0.42f, 0.26f, 0.14f};  // steel with rust
      if (variety_) random_albedo(rng_, base, accent);
      grate_mat_ = material(TextureKind::Grate, base, accent, 0.4f, 48, 0.5f);
    }
    add_panel(x, z, dir, grate_mat_, "grate");
  }

  // An alpha-tested panel (fence, grate) 2 m high on edge `dir` of cell (x, z), in a metal frame.
  void add_panel(int x, int z, int dir, int panel_material, const std::string& name) {
    Vec3 a, b;
    cell_edge(x, z, dir, a, b);
    const Vec3 inward = (grid_.centre(x, z) - (a + b) * 0.5f) * 0.08f;
    a = a + inward;
    b = b + inward;
    const float h = 2.0f;
    const int id = object();
    MeshBuilder mesh(name, panel_material, id);
    mesh.quad(a, b - a, {0, h, 0}, 2.0f * o_.texel_density / o_.texture_size);
    add(mesh);
    MeshBuilder frame(name + " frame", metal_material(), id);
    frame.cylinder(a, {0, h + 0.05f, 0}, 0.035f, 10, 1.0f);
    frame.cylinder(b, {0, h + 0.05f, 0}, 0.035f, 10, 1.0f);
    frame.tube({a + Vec3{0, h, 0}, b + Vec3{0, h, 0}}, 0.02f, 8, 1.0f);
    add(frame);
  }

  void add_sign() {
    // A panel on a wall face next to a non-wall cell (path cells included: the camera sees them).
    std::vector<std::pair<std::pair<int, int>, int>> spots;
    for (int z = 0; z < grid_.nz; ++z)
      for (int x = 0; x < grid_.nx; ++x)
        if (grid_.at(x, z) == Free || grid_.at(x, z) == Path)
          for (int d = 0; d < 4; ++d)
            if (grid_.get(x + kDx[d], z + kDz[d]) == Wall && grid_.inside(x + kDx[d], z + kDz[d]) &&
                !is_column(x + kDx[d], z + kDz[d]) &&
                !used_sign_.count(static_cast<int64_t>((z * grid_.nx + x) * 4 + d)))
              spots.push_back({{x, z}, d});
    if (spots.empty()) return;
    const auto [cell, dir] = rng_.pick(spots);
    used_sign_.insert(static_cast<int64_t>((cell.second * grid_.nx + cell.first) * 4 + dir));
    if (sign_mat_.empty() && variety_) {
      // Text panels and screens in random colours, and decals (posters, markings) of any family.
      for (int i = 0; i < 2; ++i) {
        Vec3 base, accent;
        random_albedo(rng_, base, accent);
        sign_mat_.push_back(material(TextureKind::Glyphs, base, accent, 0.2f, 32));
        scene_.materials.back().unlit = rng_.chance(0.4);
      }
      for (int i = 0; i < 2; ++i) sign_mat_.push_back(family_material());
    }
    if (sign_mat_.empty()) {
      sign_mat_.push_back(material(TextureKind::Glyphs, {0.95f, 0.9f, 0.4f}, {0.08f, 0.1f, 0.12f}, 0.2f, 32));
      sign_mat_.push_back(material(TextureKind::Glyphs, {0.3f, 0.95f, 0.5f}, {0.03f, 0.06f, 0.05f}, 0.0f, 1));
      scene_.materials.back().unlit = true;  // a glowing screen
    }
    Vec3 a, b;
    cell_edge(cell.first, cell.second, dir, a, b);
    const Vec3 mid = (a + b) * 0.5f, along = normalize(b - a);
    const Vec3 out = normalize(grid_.centre(cell.first, cell.second) - mid) * 0.02f;
    // Edges run b -> a seen from the cell, so the panel faces into the cell.
    const float w = std::min(1.4f, grid_.cell * 0.7f), h = 0.8f;
    const Vec3 origin = mid + out + along * (w / 2) + Vec3{0, 1.3f, 0};
    MeshBuilder panel("sign", rng_.pick(sign_mat_), object());
    panel.quad(origin, along * -w, {0, h, 0}, 100.0f / o_.texture_size);
    add(panel);
  }

  void add_wire() {
    // A sagging cable across a straight run of open cells, just below the ceiling (or between
    // two poles in the open).
    for (int tries = 0; tries < 30; ++tries) {
      const int x = rng_.below(grid_.nx), z = rng_.below(grid_.nz), d = rng_.below(4);
      if (grid_.get(x, z) == Wall) continue;
      int len = 0;
      while (len < 8 && grid_.get(x + kDx[d] * (len + 1), z + kDz[d] * (len + 1)) != Wall) ++len;
      if (len < 2) continue;
      // Variety: poles stand on cell boundaries; keep them off the camera's walk.
      auto on_path = [&](int cx, int cz) { return grid_.inside(cx, cz) && grid_.at(cx, cz) == Path; };
      if (variety_ && !ceiling_ &&
          (on_path(x, z) || on_path(x - kDx[d], z - kDz[d]) || on_path(x + kDx[d] * len, z + kDz[d] * len) ||
           on_path(x + kDx[d] * (len + 1), z + kDz[d] * (len + 1))))
        continue;
      const float top = ceiling_ ? wall_height_ - rng_.range(0.25f, 0.6f) : rng_.range(3.0f, 4.0f);
      const Vec3 step{kDx[d] * grid_.cell, 0, kDz[d] * grid_.cell};
      const Vec3 side{-step.z, 0, step.x};
      const Vec3 offset = side * rng_.range(-0.4f, 0.4f) / grid_.cell;
      const Vec3 a = grid_.centre(x, z, top) - step * 0.5f + offset, b = grid_.centre(x, z, top) + step * (len + 0.5f) + offset;
      const float sag = rng_.range(0.15f, 0.6f);
      std::vector<Vec3> pts;
      for (int k = 0; k <= 24; ++k) {
        const float t = k / 24.0f;
        pts.push_back(lerp(a, b, t) - Vec3{0, sag * 4 * t * (1 - t), 0});
      }
      const int id = object();
      if (wire_mat_ < 0) wire_mat_ = flat_material({0.05f, 0.05f, 0.05f}, 0.3f, 32);
      MeshBuilder w("wire", wire_mat_, id);
      w.tube(pts, rng_.range(0.008f, 0.018f), 6, 1.0f);
      if (!ceiling_) {  // poles to hang from
        w.cylinder(Vec3{a.x, 0, a.z}, {0, top + 0.05f, 0}, 0.05f, 10, 1.0f);
        w.cylinder(Vec3{b.x, 0, b.z}, {0, top + 0.05f, 0}, 0.05f, 10, 1.0f);
      }
      add(w);
      return;
    }
  }

  const ProceduralOptions& o_;
  Rng rng_;
  Scene scene_;
  Grid grid_;
  bool arena_ = false, ceiling_ = true;
  float wall_height_ = 4, uv_ = 1;
  int next_object_ = 1;
  int wall_mat_ = -1, metal_mat_ = -1, fence_mat_ = -1, wire_mat_ = -1, grate_mat_ = -1;
  bool hall_ = false, outdoor_ = false, open_sky_ = false, variety_ = false;
  std::set<int> columns_;  // hall column cells (walls for the camera walk)
  std::vector<int> sign_mat_;
  std::set<int64_t> used_sign_;
  int skipped_props_ = 0;
};

config::Schema<ProceduralProps> props_schema() {
  config::Schema<ProceduralProps> s;
  s.field("crates", &ProceduralProps::crates, "wooden crates (some stacked)").range(0, 500);
  s.field("pillars", &ProceduralProps::pillars, "columns from floor to ceiling").range(0, 500);
  s.field("spheres", &ProceduralProps::spheres, "glossy spheres on pedestals or floating").range(0, 500);
  s.field("tori", &ProceduralProps::tori, "metallic rings").range(0, 500);
  s.field("stairs", &ProceduralProps::stairs, "flights of steps with a railed landing").range(0, 100);
  s.field("fences", &ProceduralProps::fences, "chain-link fences (alpha-tested, thin)").range(0, 500);
  s.field("railings", &ProceduralProps::railings, "railings of thin posts and rails").range(0, 500);
  s.field("wires", &ProceduralProps::wires, "sagging cables under the ceiling or between poles").range(0, 500);
  s.field("signs", &ProceduralProps::signs, "wall panels with glyph-like text").range(0, 500);
  s.field("grates", &ProceduralProps::grates, "free-standing grate panels (alpha-tested bars, thin)").range(0, 500);
  return s;
}

config::Schema<ProceduralLighting> lighting_schema() {
  config::Schema<ProceduralLighting> s;
  s.field("point_lights", &ProceduralLighting::point_lights, "lamps (point lights)").range(0, 64);
  s.field("point_intensity", &ProceduralLighting::point_intensity, "lamp intensity").range(0, 1000);
  s.field("sun", &ProceduralLighting::sun, "add a directional light (always on in arenas)");
  s.field("sun_intensity", &ProceduralLighting::sun_intensity, "sun intensity").range(0, 1000);
  s.field("shadows", &ProceduralLighting::shadows, "lights cast shadows");
  s.field("ambient", &ProceduralLighting::ambient, "ambient light level (linear)").range(0, 10);
  return s;
}

config::Schema<ProceduralCamera> camera_schema() {
  config::Schema<ProceduralCamera> s;
  s.field("steps", &ProceduralCamera::steps, "cells visited by the camera walk").range(2, 10000);
  s.field("eye_height", &ProceduralCamera::eye_height, "camera height above the floor, metres").range(0.2, 3.0);
  s.field("vfov", &ProceduralCamera::vfov, "vertical field of view, degrees").range(10, 150);
  s.field("near", &ProceduralCamera::near_plane, "near plane, metres").range(1e-4, 10);
  s.field("far", &ProceduralCamera::far_plane, "far plane (depth normalization), metres").range(1, 1e7);
  s.field("yaw_sway", &ProceduralCamera::yaw_sway, "look-around amplitude, degrees").range(0, 180);
  s.field("pitch_sway", &ProceduralCamera::pitch_sway, "up/down look amplitude, degrees").range(0, 80);
  s.field("roll", &ProceduralCamera::roll, "roll amplitude, degrees").range(0, 45);
  s.field("speed_variation", &ProceduralCamera::speed_variation, "relative speed changes along the path").range(0, 0.9);
  s.validate([](const ProceduralCamera& c, const config::Cursor& at, const YAML::Node& node) {
    if (!(c.far_plane > c.near_plane)) at.fail(node, "far must be larger than near");
  });
  return s;
}

config::Schema<ProceduralFog> fog_schema() {
  config::Schema<ProceduralFog> s;
  s.field("density", &ProceduralFog::density, "fog density per metre (0 = off)").range(0, 10);
  s.field("start", &ProceduralFog::start, "distance where the fog begins, metres").at_least(0);
  s.field("color", &ProceduralFog::color, "fog colour, linear RGB")
      .range(0, 10)
      .check([](const std::vector<float>& v) { return v.size() == 3; }, "must be [r, g, b]");
  return s;
}

}  // namespace

const std::vector<std::string>& EnumNames<ProceduralLayout>::names() {
  static const std::vector<std::string> names = {"room", "corridors", "hall", "arena", "outdoor", "random"};
  return names;
}

config::Schema<ProceduralOptions> procedural_schema() {
  config::Schema<ProceduralOptions> s;
  s.field("name", &ProceduralOptions::name, "scene name");
  s.field("layout", &ProceduralOptions::layout, "level layout (random: drawn from variety.layouts)");
  s.field("variant", &ProceduralOptions::variant, "0: the level of the render seed; N: another level of the same seed")
      .range(0, 1000000000);
  s.field("size", &ProceduralOptions::size, "grid cells [x, z]")
      .range(3, 200)
      .check([](const std::vector<int>& v) { return v.size() == 2; }, "must be [cells_x, cells_z]");
  s.field("cell", &ProceduralOptions::cell, "cell size, metres").range(1.0, 20.0);
  s.field("height", &ProceduralOptions::height, "wall height, metres (arena: boundary height)").range(1.0, 50.0);
  s.field("ceiling", &ProceduralOptions::ceiling, "closed ceiling (rooms and corridors)");
  s.field("texture_size", &ProceduralOptions::texture_size, "texels per side of each texture").range(16, 2048);
  s.field("texel_density", &ProceduralOptions::texel_density, "texels per metre on walls and floors").range(1, 10000);
  s.section("props", &ProceduralOptions::props, props_schema(), "how many of each prop");
  s.section("lighting", &ProceduralOptions::lighting, lighting_schema(), "lights");
  s.section("camera", &ProceduralOptions::camera, camera_schema(), "camera fly-through");
  s.section("fog", &ProceduralOptions::fog, fog_schema(), "distance fog");
  auto rgb = [](const std::vector<float>& v) { return v.size() == 3; };
  s.field("sky_horizon", &ProceduralOptions::sky_horizon, "sky colour at the horizon, linear RGB").range(0, 10).check(rgb, "must be [r, g, b]");
  s.field("sky_zenith", &ProceduralOptions::sky_zenith, "sky colour overhead, linear RGB").range(0, 10).check(rgb, "must be [r, g, b]");
  s.section("variety", &ProceduralOptions::variety, variety_schema(),
            "ranges the layout, size, materials, lights, fog and sky are drawn from per seed (procedural_variety.h)");
  s.validate([](const ProceduralOptions& o, const config::Cursor& at, const YAML::Node& node) {
    if (o.layout != ProceduralLayout::Arena && o.layout != ProceduralLayout::Outdoor &&
        o.layout != ProceduralLayout::Random && !node["variety"] &&
        o.height < o.camera.eye_height + 0.8f)
      at.child("height").fail(node, "rooms, corridors and halls need walls at least 0.8 m above the camera's eye height");
  });
  return s;
}

uint64_t procedural_level_seed(const ProceduralOptions& options, uint64_t seed) {
  return variant_seed(seed, options.variant);
}

SceneBundle make_procedural_scene(const ProceduralOptions& options, uint64_t seed) {
  const uint64_t level_seed = procedural_level_seed(options, seed);
  ProceduralOptions drawn = options;
  drawn.variety.enabled |= options.layout == ProceduralLayout::Random;
  const ProceduralOptions level = draw_variety(drawn, level_seed);
  if (level.variety.enabled)  // what the seed drew, so a user can find a level again
    spdlog::info("procedural scene '{}': {} layout, {}x{} cells, {} point lights, fog {}", level.name, enum_name(level.layout),
                 level.size[0], level.size[1], level.lighting.point_lights, level.fog.density > 0 ? "on" : "off");
  return LevelBuilder(level, level_seed).build();
}

void register_procedural_scene_source(Registry<SceneSourceFactory>& registry) {
  registry.add(
      "procedural",
      [](const config::Block& block, uint64_t seed) {
        auto options = config::parse_block_options(block, procedural_schema());
        options.variety.enabled = block.node["variety"] && !block.node["variety"].IsNull();
        return make_procedural_scene(options, seed);
      },
      "game-like levels (rooms, corridors, halls, arenas, outdoor streets) with props, lights and a camera "
      "fly-through; a variety block draws them from the seed");
}

}  // namespace cgsr
