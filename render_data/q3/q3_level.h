#pragma once
// A parsed BSP turned into drawable geometry: triangles grouped into meshes, materials and
// textures, with the game's look approximated by one shading formula per surface.
//
// How each face is drawn (first rule that applies):
//   1. billboards (face type 4, flares)                                    -> skipped, counted
//   2. invisible: surface flag NODRAW, a shader with surfaceparm nodraw or
//      fog (fog volumes), a shader without stages, or a tool texture under
//      textures/common/ (caulk, clip, trigger, hint, skip, ...)           -> skipped, counted
//   3. sky: surface flag SKY, surfaceparm sky, or (without a shader script)
//      a name containing "sky"                                             -> sky material (the
//      scene's flat gradient, its colours taken from the sky shader's images)
//   4. transparent: the shader's first stage blends with what is behind
//      (blendFunc add / filter / blend / ...: water, glass, decals)       -> skipped, counted
//   5. alpha-tested: the colour stage has alphaFunc (grates, foliage)     -> RGBA texture, cut at 0.5
//   6. opaque.
// The colour image is the first stage that maps an image, else the shader name itself; a
// $whiteimage stage with rgbGen const gives a flat colour. Lighting:
//   lightmapped faces: albedo x lightmap x overbright, the lightmap shifted like the game does
//                      (map_overbright_bits - overbright_bits, hue-preserving clamp);
//   faces without a lightmap whose shader (or implicit shader) colours by vertex: albedo x baked
//                      vertex colour (shifted the same way) x overbright;
//   other faces without a lightmap (rgbGen identity / const): fullbright, albedo alone.
// The game computes in display (gamma) space: display = texture x lightmap x 2^overbright_bits.
// The scene shades in linear light and encodes sRGB, so lightmaps and vertex colours are marked
// sRGB and the overbright factor becomes 2^(overbright_bits x 2.2) in linear terms
// (srgb(lin(a) lin(b) 2^2.2) ~ 2ab for the sRGB curve, which is close to a 2.2 power).
//
// Positions and normals stay in Quake space here (Z up, game units); q3_scene_source converts.
// Winding is turned to the scene's convention (BSP triangles are clockwise seen from the front).
// Object ids: polygons of BSP model m get id m (the world is 0); every patch and every triangle
// mesh face gets an id of its own, so curved pieces and models outline themselves in edge maps.

#include <map>
#include <string>
#include <vector>

#include "render_data/q3/bsp_file.h"
#include "render_data/scene.h"

namespace cgsr::q3 {

class Pk3FileSystem;
class ShaderLibrary;

struct Q3LevelOptions {
  int patch_level = 8;          // quads per side of every 3x3 Bezier patch
  int overbright_bits = 1;      // the game's r_overBrightBits (display brightening: x2)
  int map_overbright_bits = 2;  // r_mapOverBrightBits, what q3map's lighting assumes
};

struct Q3LevelStats {
  int faces = 0;  // in the BSP
  int polygons = 0, patches = 0, meshes = 0;  // drawn faces by type (sky faces included)
  int sky_faces = 0, alpha_tested_faces = 0, lightmapped_faces = 0, vertex_lit_faces = 0, fullbright_faces = 0;
  int skipped_billboards = 0, skipped_invisible = 0, skipped_transparent = 0;
  int triangles = 0, patch_triangles = 0;
  int shaders_with_script = 0, shaders_without_script = 0;
  int textures_loaded = 0;
  std::vector<std::string> missing_images;      // drawn as flat grey
  std::vector<std::string> undecodable_images;  // drawn as flat grey
  int non_finite_coordinates = 0;               // from parse_bsp
  int skipped() const { return skipped_billboards + skipped_invisible + skipped_transparent; }
};

struct Q3Level {
  Scene scene;  // positions and normals in QUAKE space; textures, materials, sky final
  Q3LevelStats stats;
};

Q3Level build_level(const BspFile& bsp, const ShaderLibrary& shaders, const Pk3FileSystem& files,
                    const Q3LevelOptions& options);

// The game's lighting shift: each byte << shift, then scaled down as a colour (hue kept) if a
// channel exceeds 255. Used on lightmaps and vertex colours.
std::array<uint8_t, 3> shift_lighting(const uint8_t* rgb, int shift);

// Linear multiplier equivalent to the game's display overbright (see above).
float overbright_factor(int overbright_bits);

}  // namespace cgsr::q3
