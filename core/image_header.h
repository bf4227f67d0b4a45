#pragma once
// The size an image file declares, read from its header without decoding it: a 1 MB PNG can
// declare 20000x20000 pixels, and decoders allocate what the header says. Knows the formats cgsr
// reads: PNG, JPEG, PPM/PGM, BMP, TIFF and OpenEXR.

#include <cstdint>
#include <filesystem>
#include <string>

namespace cgsr {

struct ImageHeader {
  std::string format;  // "PNG", "JPEG", "PNM", "BMP", "TIFF", "EXR"
  int64_t width = 0, height = 0;
};

// The largest image cgsr decodes: a side and a pixel count (16384 x 8192).
constexpr int64_t kMaxImageSide = 16384;
constexpr int64_t kMaxImagePixels = int64_t{1} << 27;

// Throws a user error at `context` when `header` declares no pixels or more than those limits.
void check_image_limits(const ImageHeader& header, const std::string& context);

// Throws a user error naming the file when it is none of those formats or its header is cut short
// or inconsistent.
ImageHeader read_image_header(const std::filesystem::path& path);

// The same for bytes in memory (the first bytes of a file suffice for every format but JPEG,
// whose size follows its metadata segments).
ImageHeader parse_image_header(const std::string& bytes, const std::string& context);

}  // namespace cgsr
