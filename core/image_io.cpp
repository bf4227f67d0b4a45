#include "core/image_io.h"

#include <algorithm>
#include <cstdlib>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_header.h"
#include "core/tensor_checks.h"

namespace cgsr {
namespace fs = std::filesystem;

namespace {
// OpenCV reads EXR only when this is set before its first use of the codec.
void enable_exr() {
  static const bool once = [] {
    ::setenv("OPENCV_IO_ENABLE_OPENEXR", "1", /*overwrite=*/0);
    return true;
  }();
  (void)once;
}

std::string lower_extension(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
  return ext;
}

int check_bits(const std::string& ext, int bits, const std::string& context) {
  const bool is_float_format = ext == ".exr";
  const bool supports_16 = ext == ".png" || ext == ".ppm" || ext == ".pgm" || ext == ".tif" || ext == ".tiff";
  const bool supports_32 = ext == ".tif" || ext == ".tiff" || ext == ".exr";
  if (ext != ".png" && ext != ".ppm" && ext != ".pgm" && ext != ".bmp" && ext != ".tif" && ext != ".tiff" &&
      ext != ".exr")
    throw Error(context, "unsupported image format '" + ext + "' (use .png, .ppm, .pgm, .bmp, .tif, .exr)");
  if (is_float_format) return 32;
  if (bits == 8) return 8;
  if (bits == 16 && supports_16) return 16;
  if (bits == 32 && supports_32) return 32;
  throw Error(context, std::to_string(bits) + "-bit is not supported for " + ext);
}

cv::Mat to_mat(const torch::Tensor& image, int bits, const std::string& context) {
  torch::Tensor t = image;
  if (t.dim() == 2) t = t.unsqueeze(0);
  if (t.dim() != 3 || (t.size(0) != 1 && t.size(0) != 3 && t.size(0) != 4))
    throw Error(context, "expected a CHW image with 1, 3 or 4 channels, got shape " + shape_string(image));
  require_finite(t, context);
  t = t.to(torch::kFloat32).permute({1, 2, 0}).contiguous();  // HWC
  const int h = static_cast<int>(t.size(0)), w = static_cast<int>(t.size(1)), c = static_cast<int>(t.size(2));
  cv::Mat mat;
  if (bits == 32) {
    mat = cv::Mat(h, w, CV_32FC(c), t.data_ptr<float>()).clone();
  } else {
    const double max_value = bits == 16 ? 65535.0 : 255.0;
    t = (t.clamp(0.0, 1.0) * max_value).round();
    if (bits == 16) {
      auto u = t.to(torch::kInt32).contiguous();
      cv::Mat(h, w, CV_32SC(c), u.data_ptr<int32_t>()).convertTo(mat, CV_16UC(c));
    } else {
      auto u = t.to(torch::kUInt8).contiguous();
      mat = cv::Mat(h, w, CV_8UC(c), u.data_ptr<uint8_t>()).clone();
    }
  }
  if (c == 3) cv::cvtColor(mat, mat, cv::COLOR_RGB2BGR);
  if (c == 4) cv::cvtColor(mat, mat, cv::COLOR_RGBA2BGRA);
  return mat;
}
// Before decoding: the decoder allocates whatever the header declares.
void check_declared_size(const ImageHeader& header, const ImageReadOptions& options, const std::string& context) {
  // Worded as the decoded size check of the data-set readers, which `data check` counts by it.
  if (options.width > 0 && options.height > 0 && (header.width != options.width || header.height != options.height))
    throw Error(context, "size " + std::to_string(header.width) + "x" + std::to_string(header.height) + " (from the " +
                             header.format + " header; not decoded) does not match the resolution " +
                             std::to_string(options.width) + "x" + std::to_string(options.height));
  check_image_limits(header, context);  // also for a frame size that is itself too large
}
}  // namespace

torch::Tensor read_image(const fs::path& path, const ImageReadOptions& options) {
  return read_image_file(path, options).pixels;
}

ImageFile read_image_file(const fs::path& path, const ImageReadOptions& options) {
  enable_exr();
  const std::string context = path.string();
  if (!fs::exists(path)) throw Error(context, "no such image file");
  check_declared_size(read_image_header(path), options, context);
  cv::Mat mat = cv::imread(path.string(), cv::IMREAD_UNCHANGED | cv::IMREAD_ANYDEPTH | cv::IMREAD_ANYCOLOR);
  if (mat.empty()) throw Error(context, "unreadable image (corrupt, truncated or an unsupported format)");
  const int c = mat.channels();
  if (c != 1 && c != 3 && c != 4) throw Error(context, "unsupported channel count " + std::to_string(c));
  if (options.channels && options.channels != c)
    throw Error(context, "has " + std::to_string(c) + " channel(s), expected " + std::to_string(options.channels));
  if (c == 3) cv::cvtColor(mat, mat, cv::COLOR_BGR2RGB);
  if (c == 4) cv::cvtColor(mat, mat, cv::COLOR_BGRA2RGBA);

  cv::Mat as_float;
  ImageFile out;
  switch (mat.depth()) {
    case CV_8U: mat.convertTo(as_float, CV_32F, 1.0 / 255.0), out.bits = 8; break;
    case CV_16U: mat.convertTo(as_float, CV_32F, 1.0 / 65535.0), out.bits = 16; break;
    case CV_32F: as_float = mat, out.bits = 32; break;
    default: throw Error(context, "unsupported bit depth (expected 8-bit, 16-bit or 32-bit float)");
  }
  as_float = as_float.isContinuous() ? as_float : as_float.clone();
  auto hwc = torch::from_blob(as_float.data, {as_float.rows, as_float.cols, c}, torch::kFloat32);
  // clone(): for one channel the permuted view is already "contiguous", and contiguous() would
  // return a view of the cv::Mat's memory, which is freed on return.
  out.pixels = hwc.permute({2, 0, 1}).clone(at::MemoryFormat::Contiguous);
  return out;
}

std::vector<unsigned char> encode_image(const std::string& extension, const torch::Tensor& image,
                                        const ImageWriteOptions& options) {
  enable_exr();
  std::string ext = extension;
  std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
  const int bits = check_bits(ext, options.bits, "image" + ext);
  const cv::Mat mat = to_mat(image, bits, "image" + ext);
  std::vector<int> params;
  if (ext == ".png") params = {cv::IMWRITE_PNG_COMPRESSION, 6};
  if (ext == ".exr") params = {cv::IMWRITE_EXR_TYPE, cv::IMWRITE_EXR_TYPE_FLOAT};
  // OpenCV's default for float TIFF is SGILOG, which is lossy; LZW is lossless.
  if (ext == ".tif" || ext == ".tiff") params = {cv::IMWRITE_TIFF_COMPRESSION, 5};
  std::vector<unsigned char> bytes;
  if (!cv::imencode(ext, mat, bytes, params)) throw Error("image" + ext, "OpenCV could not encode the image");
  return bytes;
}

void write_image(const fs::path& path, const torch::Tensor& image, const ImageWriteOptions& options) {
  std::vector<unsigned char> bytes;
  try {
    bytes = encode_image(lower_extension(path), image, options);
  } catch (const Error& e) {
    throw Error(path.string(), e.message(), e.kind());
  }
  write_file_atomic(path, std::string(bytes.begin(), bytes.end()));
}

}  // namespace cgsr
