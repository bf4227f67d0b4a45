#include "render_data/q3/texture_resolver.h"

#include <stb_image.h>

#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "core/image_header.h"
#include "render_data/q3/pk3_archive.h"
#include "render_data/q3/script_tokens.h"

namespace cgsr::q3 {
namespace {

const char* const kExtensions[] = {".tga", ".jpg", ".png", ".jpeg"};

std::string extension_of(const std::string& name) {
  const size_t dot = name.find_last_of('.');
  const size_t slash = name.find_last_of('/');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  return ascii_lower(name.substr(dot));
}

Texture from_rgba(const uint8_t* rgba, int width, int height, const std::string& name, bool keep_alpha) {
  Texture t;
  t.name = name;
  t.width = width;
  t.height = height;
  t.channels = keep_alpha ? 4 : 3;
  t.srgb = true;
  const size_t pixels = static_cast<size_t>(width) * height;
  t.data.resize(pixels * t.channels);
  for (size_t i = 0; i < pixels; ++i)
    for (int c = 0; c < t.channels; ++c) t.data[i * t.channels + c] = rgba[i * 4 + c];
  return t;
}

// The size the image declares, from its header alone (stb_image reads a TGA's, core/image_header.h
// the others'), so that a small file declaring a huge image is refused before a decoder allocates it.
ImageHeader declared_size(const std::vector<uint8_t>& bytes, const std::string& name) {
  if (extension_of(name) == ".tga") {
    int width = 0, height = 0, channels = 0;
    if (!stbi_info_from_memory(bytes.data(), static_cast<int>(bytes.size()), &width, &height, &channels))
      throw Error(name, std::string("cannot decode TGA: ") + stbi_failure_reason());
    return {"TGA", width, height};
  }
  return parse_image_header(std::string(bytes.begin(), bytes.end()), name);
}

}  // namespace

Texture decode_image(const std::vector<uint8_t>& bytes, const std::string& name, bool keep_alpha) {
  if (bytes.empty()) throw Error(name, "image file is empty");
  if (bytes.size() > static_cast<size_t>(std::numeric_limits<int>::max())) throw Error(name, "image file is too large");
  check_image_limits(declared_size(bytes, name), name);
  if (extension_of(name) == ".tga") {
    int width = 0, height = 0, channels = 0;
    std::unique_ptr<stbi_uc, void (*)(void*)> pixels(
        stbi_load_from_memory(bytes.data(), static_cast<int>(bytes.size()), &width, &height, &channels, 4),
        stbi_image_free);
    if (!pixels) throw Error(name, std::string("cannot decode TGA: ") + stbi_failure_reason());
    return from_rgba(pixels.get(), width, height, name, keep_alpha);
  }
  const cv::Mat encoded(1, static_cast<int>(bytes.size()), CV_8UC1, const_cast<uint8_t*>(bytes.data()));
  cv::Mat image;
  try {
    image = cv::imdecode(encoded, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    throw Error(name, std::string("cannot decode image: ") + e.what());
  }
  if (image.empty()) throw Error(name, "cannot decode image (not a valid JPG/PNG)");
  if (image.depth() != CV_8U) image.convertTo(image, CV_8U, image.depth() == CV_16U ? 1.0 / 257 : 255.0);
  cv::Mat rgba;
  switch (image.channels()) {
    case 1: cv::cvtColor(image, rgba, cv::COLOR_GRAY2RGBA); break;
    case 3: cv::cvtColor(image, rgba, cv::COLOR_BGR2RGBA); break;
    case 4: cv::cvtColor(image, rgba, cv::COLOR_BGRA2RGBA); break;
    default: throw Error(name, "image has " + std::to_string(image.channels()) + " channels");
  }
  if (!rgba.isContinuous()) rgba = rgba.clone();
  return from_rgba(rgba.data, rgba.cols, rgba.rows, name, keep_alpha);
}

std::optional<std::string> TextureResolver::find(const std::string& name) const {
  const std::string path = normalize_game_path(name);
  if (!extension_of(path).empty() && files_.contains(path)) return path;
  const std::string ext = extension_of(path);
  const std::string stem = ext.empty() ? path : path.substr(0, path.size() - ext.size());
  for (const char* candidate : kExtensions)
    if (files_.contains(stem + candidate)) return stem + candidate;
  return std::nullopt;
}

}  // namespace cgsr::q3
