#include "core/image_header.h"

#include <cctype>
#include <cstring>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

#include "core/error.h"

namespace cgsr {
namespace {

const char* const kCutShort = "the image header is cut short";

// Bounds-checked reads of the header bytes; a read past the end is a truncated header.
class Bytes {
 public:
  Bytes(const std::string& data, const std::string& context) : data_(data), context_(context) {}
  size_t size() const { return data_.size(); }
  uint8_t u8(size_t at) const {
    need(at, 1);
    return static_cast<uint8_t>(data_[at]);
  }
  uint32_t be(size_t at, int n) const {
    need(at, n);
    uint32_t v = 0;
    for (int i = 0; i < n; ++i) v = (v << 8) | u8(at + i);
    return v;
  }
  uint32_t le(size_t at, int n) const {
    need(at, n);
    uint32_t v = 0;
    for (int i = n - 1; i >= 0; --i) v = (v << 8) | u8(at + i);
    return v;
  }
  bool starts_with(const std::string& magic) const { return data_.compare(0, magic.size(), magic) == 0; }
  [[noreturn]] void fail(const std::string& what) const { throw Error(context_, "unreadable image: " + what); }
  void need(size_t at, size_t n) const {
    if (at > data_.size() || n > data_.size() - at) fail(kCutShort);
  }
  const std::string& data() const { return data_; }

 private:
  const std::string& data_;
  std::string context_;
};

ImageHeader png(const Bytes& b) {
  // Signature, then the IHDR chunk: length, "IHDR", width, height (big-endian).
  b.need(12, 4);
  if (b.data().compare(12, 4, "IHDR") != 0) b.fail("a PNG file whose first chunk is not IHDR");
  return {"PNG", b.be(16, 4), b.be(20, 4)};
}

ImageHeader jpeg(const Bytes& b) {
  size_t at = 2;
  while (true) {
    if (b.u8(at) != 0xFF) b.fail("a JPEG file with a broken marker at byte " + std::to_string(at));
    while (b.u8(at) == 0xFF) ++at;  // fill bytes
    const uint8_t marker = b.u8(at++);
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) continue;  // no length
    if (marker == 0xD9 || marker == 0xDA) b.fail("a JPEG file without a frame header before its image data");
    const uint32_t length = b.be(at, 2);
    if (length < 2) b.fail("a JPEG file with a segment of length " + std::to_string(length));
    // Start of frame: every SOFn but DHT (C4), JPG (C8) and DAC (CC).
    if (marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC)
      return {"JPEG", b.be(at + 5, 2), b.be(at + 3, 2)};
    at += length;
  }
}

ImageHeader pnm(const Bytes& b) {
  // "P5 <width> <height> ...", whitespace and '#' comments between the fields.
  size_t at = 2;
  const auto number = [&]() -> int64_t {
    while (true) {
      const char c = static_cast<char>(b.u8(at));
      if (c == '#') {
        while (b.u8(at) != '\n') ++at;
      } else if (std::isspace(static_cast<unsigned char>(c))) {
        ++at;
      } else {
        break;
      }
    }
    if (!std::isdigit(b.u8(at))) b.fail("a PPM/PGM header without its width and height");
    int64_t v = 0;
    while (std::isdigit(b.u8(at))) {
      v = v * 10 + (b.u8(at++) - '0');
      if (v > (int64_t{1} << 31)) b.fail("a PPM/PGM header declaring a size beyond 2^31");
    }
    return v;
  };
  const int64_t width = number();
  return {"PNM", width, number()};
}

ImageHeader bmp(const Bytes& b) {
  const uint32_t info_size = b.le(14, 4);
  if (info_size == 12) return {"BMP", b.le(18, 2), b.le(20, 2)};  // OS/2 core header
  const int64_t width = static_cast<int32_t>(b.le(18, 4));
  const int64_t height = static_cast<int32_t>(b.le(22, 4));  // negative: stored top-down
  return {"BMP", width < 0 ? -width : width, height < 0 ? -height : height};
}

ImageHeader tiff(const Bytes& b) {
  const bool little = b.u8(0) == 'I';
  const auto read = [&](size_t at, int n) { return little ? b.le(at, n) : b.be(at, n); };
  if (read(2, 2) != 42) b.fail("a TIFF file of a kind cgsr does not read (BigTIFF?)");
  const size_t ifd = read(4, 4);
  const uint32_t entries = read(ifd, 2);
  ImageHeader h{"TIFF", -1, -1};
  for (uint32_t i = 0; i < entries; ++i) {
    const size_t e = ifd + 2 + 12 * static_cast<size_t>(i);
    const uint32_t tag = read(e, 2), type = read(e + 2, 2);
    if (tag != 256 && tag != 257) continue;
    const int64_t value = type == 3 ? read(e + 8, 2) : read(e + 8, 4);  // SHORT or LONG
    int64_t& side = tag == 256 ? h.width : h.height;
    // A decoder may take either of two: the size checked must be the one decoded.
    if (side >= 0) b.fail("a TIFF file with its width or height tag twice");
    side = value;
  }
  if (h.width < 0 || h.height < 0) b.fail("a TIFF file without its width and height tags");
  return h;
}

// The value size OpenEXR reads for each attribute type it knows with a fixed size; it reads
// that many bytes whatever the header's size field says, so the field must agree.
int64_t exr_fixed_size(const std::string& type) {
  static const std::map<std::string, int64_t> sizes = {
      {"box2i", 16}, {"box2f", 16}, {"chromaticities", 32}, {"compression", 1}, {"double", 8}, {"envmap", 1},
      {"float", 4},  {"int", 4},    {"keycode", 28},        {"lineOrder", 1},   {"m33f", 36},  {"m33d", 72},
      {"m44f", 64},  {"m44d", 128}, {"rational", 8},        {"tiledesc", 9},    {"timecode", 8}, {"v2i", 8},
      {"v2f", 8},    {"v2d", 16},   {"v3i", 12},            {"v3f", 12},        {"v3d", 24},   {"deepImageState", 1}};
  const auto it = sizes.find(type);
  return it == sizes.end() ? -1 : it->second;
}

ImageHeader exr(const Bytes& b) {
  // Magic and version, then attributes "name\0type\0<int32 size><value>" up to an empty name.
  // The header is walked as OpenEXR reads it, so that no attribute it reads can make it allocate
  // more than the file holds: names of at most 255 bytes, the fixed-size types at their size, a
  // channel list read to its end, and value sizes within the file (an unknown type is read as
  // that many bytes). Types whose values allocate by their content (preview images, string
  // vectors, ID manifests) and deep or multi-part files (more headers) are refused.
  const uint32_t flags = b.le(4, 4) & ~0xffu;
  if (flags & ~0x600u) b.fail("an OpenEXR file that is deep or multi-part");
  const auto name_at = [&](size_t at, const char* what) {
    const size_t end = b.data().find('\0', at);
    if (end == std::string::npos) b.fail(kCutShort);
    if (end - at > 255) b.fail(std::string("an OpenEXR ") + what + " longer than 255 bytes");
    return b.data().substr(at, end - at);
  };
  // The whole header is read: OpenEXR takes the last of two dataWindows, so two are refused.
  size_t at = 8;
  std::optional<ImageHeader> found;
  while (true) {
    const std::string name = name_at(at, "attribute name");
    if (name.empty()) break;
    const size_t type_at = at + name.size() + 1;
    const std::string type = name_at(type_at, "attribute type");
    const size_t size_at = type_at + type.size() + 1;
    const int32_t size = static_cast<int32_t>(b.le(size_at, 4));
    const size_t value = size_at + 4;
    if (size < 0) b.fail("an OpenEXR attribute of negative size");
    b.need(value, static_cast<size_t>(size));
    if (type == "preview" || type == "stringvector" || type == "idmanifest")
      b.fail("an OpenEXR '" + type + "' attribute (cgsr's frames have none)");
    const int64_t fixed = exr_fixed_size(type);
    if (fixed >= 0 && size != fixed)
      b.fail("an OpenEXR '" + type + "' attribute of " + std::to_string(size) + " bytes, not " + std::to_string(fixed));
    if (type == "chlist") {  // channels "name\0" + 16 bytes each, up to an empty name
      size_t c = value;
      for (std::string channel; !(channel = name_at(c, "channel name")).empty();) c += channel.size() + 1 + 16;
      if (c + 1 != value + static_cast<size_t>(size)) b.fail("an OpenEXR channel list whose size disagrees with it");
    }
    if (name == "dataWindow") {
      if (found) b.fail("an OpenEXR header with two dataWindows");
      if (type != "box2i") b.fail("an OpenEXR dataWindow that is not a box2i");
      const auto i32 = [&](size_t k) { return static_cast<int64_t>(static_cast<int32_t>(b.le(value + 4 * k, 4))); };
      const int64_t width = i32(2) - i32(0) + 1, height = i32(3) - i32(1) + 1;
      if (width < 1 || height < 1) b.fail("an OpenEXR dataWindow of no pixels");
      found = ImageHeader{"EXR", width, height};
    }
    at = value + static_cast<size_t>(size);
  }
  if (!found) b.fail("an OpenEXR header without a dataWindow");
  return *found;
}

}  // namespace

ImageHeader parse_image_header(const std::string& bytes, const std::string& context) {
  const Bytes b(bytes, context);
  if (b.starts_with("\x89PNG\r\n\x1a\n")) return png(b);
  if (b.starts_with("\xFF\xD8")) return jpeg(b);
  if (b.size() >= 2 && b.u8(0) == 'P' && b.u8(1) >= '1' && b.u8(1) <= '6') return pnm(b);
  if (b.starts_with("BM")) return bmp(b);
  if (b.starts_with(std::string("II*\0", 4)) || b.starts_with(std::string("MM\0*", 4))) return tiff(b);
  if (b.starts_with("\x76\x2f\x31\x01")) return exr(b);
  throw Error(context, "unreadable image: not a format cgsr reads (PNG, JPEG, PPM/PGM, BMP, TIFF or OpenEXR)");
}

void check_image_limits(const ImageHeader& header, const std::string& context) {
  if (header.width >= 1 && header.height >= 1 && header.width <= kMaxImageSide && header.height <= kMaxImageSide &&
      header.width * header.height <= kMaxImagePixels)
    return;
  throw Error(context, "the " + header.format + " header declares " + std::to_string(header.width) + "x" +
                           std::to_string(header.height) + " pixels, beyond the limit of " +
                           std::to_string(kMaxImageSide) + " a side and " + std::to_string(kMaxImagePixels) +
                           " pixels (the file was not decoded)");
}

ImageHeader read_image_header(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path.string(), "cannot read the image file");
  // Headers sit in the first bytes, but JPEG metadata (EXIF thumbnails) and TIFF directories may
  // push the size further: 64 KiB first, 4 MiB when that is not enough.
  std::string head;
  for (const size_t limit : {size_t{1} << 16, size_t{1} << 22}) {
    head.resize(limit);
    in.clear();
    in.seekg(0);
    in.read(head.data(), static_cast<std::streamsize>(limit));
    head.resize(static_cast<size_t>(in.gcount()));
    try {
      return parse_image_header(head, path.string());
    } catch (const Error& e) {
      const std::string what = e.message();
      const bool cut_short = what.size() >= std::strlen(kCutShort) &&
                             what.compare(what.size() - std::strlen(kCutShort), std::string::npos, kCutShort) == 0;
      if (!cut_short || head.size() < limit) throw;
    }
  }
  return parse_image_header(head, path.string());
}

}  // namespace cgsr
