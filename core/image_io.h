#pragma once
// Image files <-> CPU float32 CHW tensors.
//   read:  8-bit and 16-bit PNG/PPM/PGM/BMP/TIFF/JPEG scaled to [0,1]; 32-bit float TIFF and EXR
//          as stored. The size a file declares is read from its header first
//          (core/image_header.h) and checked before it is decoded.
//   write: the encoding follows the extension and `bits` (8 or 16 for PNG/PPM/TIFF, 32 for float
//          TIFF and EXR); integer encodings clamp to [0,1] and round.
// Colour channels are RGB in memory (OpenCV's BGR order is undone here, once).

#include <torch/types.h>

#include <filesystem>
#include <string>
#include <vector>

namespace cgsr {

struct ImageReadOptions {
  int channels = 0;  // expected channel count (1, 3 or 4); 0 accepts any
  // The size the file must declare in its header, checked before anything is decoded (a small
  // file may declare a huge image); 0: unknown. Either way the size must be within the limits of
  // core/image_header.h.
  int width = 0, height = 0;
};

struct ImageWriteOptions {
  int bits = 8;  // 8, 16 or 32 (float)
};

// An image as read, with how it was stored: captures need the bit depth to know how precise
// (depth) or how to unpack (motion vectors) their values are.
struct ImageFile {
  torch::Tensor pixels;  // float32 CHW; integers scaled to [0,1]
  int bits = 8;          // 8 or 16 (integer), 32 (float)
  bool is_float() const { return bits == 32; }
  double max_code() const { return bits == 16 ? 65535.0 : 255.0; }  // of an integer image
};

ImageFile read_image_file(const std::filesystem::path& path, const ImageReadOptions& options = {});
torch::Tensor read_image(const std::filesystem::path& path, const ImageReadOptions& options = {});

// `image` is CHW (C = 1, 3 or 4) or HW. Written atomically. Non-finite values are an error.
void write_image(const std::filesystem::path& path, const torch::Tensor& image, const ImageWriteOptions& options = {});

// Encodes to memory with the format of `extension` (".png", ...): for size reports and tests.
std::vector<unsigned char> encode_image(const std::string& extension, const torch::Tensor& image,
                                        const ImageWriteOptions& options = {});

}  // namespace cgsr
