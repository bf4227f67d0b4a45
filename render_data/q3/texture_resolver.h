#pragma once
// Finds and decodes the images a map's shaders name. The game asks for "textures/x/y" (or
// "textures/x/y.tga" from a shader stage) and accepts whichever of .tga, .jpg, .png exists in the
// pk3 file system; the newest archive wins. TGA is decoded with stb_image (Debian libstb), JPG and
// PNG with OpenCV.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "render_data/scene.h"

namespace cgsr::q3 {

class Pk3FileSystem;

// Decodes TGA/JPG/PNG bytes to an 8-bit RGB (keep_alpha false) or RGBA texture, rows top to
// bottom (TGA's bottom-up origin is undone). cgsr::Error naming `name` when it cannot, or when
// its header declares more than core/image_header.h's limits (checked before decoding).
Texture decode_image(const std::vector<uint8_t>& bytes, const std::string& name, bool keep_alpha);

class TextureResolver {
 public:
  explicit TextureResolver(const Pk3FileSystem& files) : files_(files) {}

  // The stored name of the image `name` refers to (extension replaced as the game does), or
  // nullopt when no archive holds any of the candidates.
  std::optional<std::string> find(const std::string& name) const;

 private:
  const Pk3FileSystem& files_;
};

}  // namespace cgsr::q3
