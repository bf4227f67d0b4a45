#pragma once
// The in-memory scene: what every scene source (procedural generator, Quake III BSP loader, ...)
// produces and the rasterizer consumes. Plain data with no renderer state, so any loader can
// fill it; validate_scene() checks it before rendering.
//
// Conventions (all sources must follow them):
//   world space   right-handed, +y up, units are metres (a loader converts its own axes/units).
//   colours       tints, light colours, sky and fog colours are LINEAR RGB; texture bytes are
//                 sRGB-encoded unless Texture::srgb is false. The renderer shades in linear RGB
//                 and writes sRGB-encoded colour frames.
//   winding       a triangle's front face is counter-clockwise seen from the front; only
//                 materials with two_sided = false cull back faces.
//   uv            (0,0) is the first texel of the first row of the texture data (top-left);
//                 textures repeat outside [0,1).
//   camera        yaw rotates about world +y (0 looks along -z, positive turns left), pitch
//                 about the camera's right axis (positive looks up), roll about the viewing
//                 direction (positive tilts the image clockwise); angles in degrees.

#include <cstdint>
#include <string>
#include <vector>

#include "render_data/vec_math.h"

namespace cgsr {

// A texture as stored: the rasterizer builds (and caches) its own mip chain from it.
struct Texture {
  std::string name;
  int width = 0, height = 0;
  int channels = 3;           // 3 (RGB) or 4 (RGBA; alpha is linear coverage for alpha testing)
  bool srgb = true;           // bytes are sRGB-encoded (albedo); false: linear (e.g. lightmaps)
  std::vector<uint8_t> data;  // width * height * channels bytes, rows top to bottom
};

struct Material {
  std::string name;
  int albedo_texture = -1;  // index into Scene::textures; -1: a flat colour (tint alone)
  Vec3 tint{1, 1, 1};       // linear multiplier of the albedo
  // When set, the shaded colour is albedo x lightmap x lightmap_scale (baked lighting, as in
  // Quake III): dynamic lights, shadows and specular are not applied. Sampled with the mesh's
  // lightmap_uvs, bilinear without mipmaps.
  int lightmap_texture = -1;
  float lightmap_scale = 1.0f;  // overbright factor applied to the (linear) lightmap value
  float specular = 0.0f;        // Blinn-Phong specular strength
  float shininess = 32.0f;      // Blinn-Phong exponent
  float alpha_cutoff = 0.0f;    // > 0: texels with alpha below it are holes (fences, grates)
  bool unlit = false;           // colour = albedo (emissive surfaces, sprites)
  bool sky = false;             // draws the sky colour; depth = +inf, no normal, no edges inside
  bool two_sided = true;        // false: back faces are culled
};

struct Mesh {
  std::string name;
  std::vector<Vec3> positions;     // world space
  std::vector<Vec3> normals;       // per vertex, unit length, world space
  std::vector<Vec2> uvs;           // per vertex (albedo texture coordinates)
  std::vector<Vec2> lightmap_uvs;  // empty, or per vertex (material lightmap coordinates)
  std::vector<Vec3> colors;        // empty, or per vertex linear RGB multiplied into the albedo
  std::vector<uint32_t> indices;   // three per triangle
  int material = 0;                // index into Scene::materials
  int object_id = 0;               // >= 0; surfaces of one object share it (edges at id changes)
};

enum class LightType { Point, Directional };

struct Light {
  LightType type = LightType::Point;
  Vec3 position{0, 0, 0};    // point lights, world space
  Vec3 direction{0, -1, 0};  // directional lights: the direction the light travels
  Vec3 color{1, 1, 1};       // linear RGB
  float intensity = 1.0f;    // directional: irradiance scale; point: intensity / (1 + (d / radius)^2)
  float radius = 5.0f;       // point lights: distance at which the intensity has halved
  bool shadows = false;      // cast shadows (shadow map) when the renderer enables shadows
};

// Background where no geometry is hit (and on sky materials): a vertical gradient from the
// horizon colour (view direction level or below) to the zenith colour (straight up).
struct Sky {
  Vec3 horizon{0.55f, 0.65f, 0.8f};  // linear RGB
  Vec3 zenith{0.15f, 0.3f, 0.65f};   // equal to horizon for a flat colour
};

// Distance fog: colour = lerp(surface, fog colour, 1 - exp(-density * max(0, distance - start))).
struct Fog {
  float density = 0.0f;  // per metre; 0 disables fog
  float start = 0.0f;    // metres from the camera where the fog begins
  Vec3 color{0.5f, 0.55f, 0.6f};  // linear RGB
};

struct Scene {
  std::string name;
  std::vector<Mesh> meshes;
  std::vector<Material> materials;
  std::vector<Texture> textures;
  std::vector<Light> lights;
  Vec3 ambient{0.08f, 0.08f, 0.1f};  // linear RGB added to the lit colour before the albedo product
  Sky sky;
  Fog fog;
};

// One camera at one frame.
struct CameraPose {
  Vec3 position{0, 0, 0};
  float yaw = 0, pitch = 0, roll = 0;  // degrees, see the conventions above
  float vfov = 60;                     // vertical field of view, degrees
};

// A smooth camera path: Catmull-Rom interpolation of key poses at increasing key times. Key times
// encode speed changes (a long gap between two close keys is a slow stretch). A sequence of N
// frames traverses the whole path: frame i is at time t0 + (t1 - t0) * i / (N - 1). Angles are
// interpolated as numbers (not wrapped), so a source writes continuous yaw values.
struct CameraKey {
  double time = 0;
  CameraPose pose;
};

struct CameraPath {
  std::vector<CameraKey> keys;  // at least one; times strictly increasing
  float near_plane = 0.05f;     // clip and normalization planes, metres (far may be large)
  float far_plane = 500.0f;

  CameraPose at_time(double time) const;  // clamped to the key range
  // Pose at frame `frame` of a sequence of `frames` frames (frames >= 1; frame may be -1 or
  // beyond the end, where the path is clamped).
  CameraPose at_frame(int frame, int frames) const;
};

// A scene source's product.
struct SceneBundle {
  Scene scene;
  CameraPath camera;
};

// Throws cgsr::Error naming the scene and mesh/material/texture when an index is out of range,
// sizes disagree, a value is not finite, or the camera path is malformed.
void validate_scene(const Scene& scene);
void validate_camera_path(const CameraPath& path, const std::string& context);

// Bounding box of all mesh positions ({inf,...} / {-inf,...} when there are none).
void scene_bounds(const Scene& scene, Vec3& lo, Vec3& hi);
size_t triangle_count(const Scene& scene);

}  // namespace cgsr
