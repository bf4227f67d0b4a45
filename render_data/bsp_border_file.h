#pragma once
// The file of a frame's sub-pixel BSP border image (bsp_border.h) in a cgsr data set:
// <root>/<W>x<H>/bsp_border/<frame:06d>.bsp, written atomically. The format (little-endian,
// docs/bsp_border.md):
//
//   header (28 bytes)  char[8] "CGSRBSPB", u32 version (1), u32 width, u32 height, u32 max_depth,
//                      u32 count (border pixels)
//   count records      u32 pixel (row * width + column, strictly ascending), u8 lines L
//                      (1 .. 2^max_depth - 1), u32 shape (preorder, bit k set: node k is a split),
//                      L x f32[3] line (a, b, c), (L + 1) x u8[3] leaf colour (sRGB)
//
// The reader validates every field and throws cgsr::Error whose context is the file and whose
// message names the frame, the field and what is wrong.

#include <filesystem>
#include <string>

#include "render_data/bsp_border.h"
#include "render_data/dataset_manifest.h"

namespace cgsr {

constexpr int kBspBorderFileVersion = 1;

std::filesystem::path bsp_border_file(const std::filesystem::path& root, const Resolution& resolution, int frame);

std::string encode_bsp_border(const BspBorderImage& image);
// `context` names the source (the file) in errors; `frame` is only used in messages.
BspBorderImage decode_bsp_border(const std::string& bytes, const std::string& context, int frame,
                                 const Resolution& expected);

void write_bsp_border_file(const std::filesystem::path& path, const BspBorderImage& image);  // atomic
BspBorderImage read_bsp_border_file(const std::filesystem::path& path, int frame, const Resolution& expected);

}  // namespace cgsr
