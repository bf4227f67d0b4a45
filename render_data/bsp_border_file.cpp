#include "render_data/bsp_border_file.h"

#include <cstdio>
#include <cstring>

#include "core/atomic_file.h"
#include "core/error.h"

namespace cgsr {
namespace fs = std::filesystem;

namespace {
constexpr char kMagic[8] = {'C', 'G', 'S', 'R', 'B', 'S', 'P', 'B'};
constexpr size_t kHeaderBytes = 28;

void put_u32(std::string& out, uint32_t v) {
  for (int k = 0; k < 4; ++k) out.push_back(static_cast<char>((v >> (8 * k)) & 0xffu));
}
void put_f32(std::string& out, float f) {
  uint32_t v;
  std::memcpy(&v, &f, 4);
  put_u32(out, v);
}

// Reads fields in order; a read past the end throws naming the field.
class Reader {
 public:
  Reader(const std::string& bytes, std::string context, int frame)
      : bytes_(bytes), context_(std::move(context)), frame_(frame) {}
  [[noreturn]] void fail(const std::string& field, const std::string& what) const {
    throw Error(context_, "frame " + std::to_string(frame_) + ": " + field + ": " + what);
  }
  void need(size_t n, const std::string& field) const {
    if (bytes_.size() - at_ < n)
      fail(field, "truncated: needs " + std::to_string(n) + " byte(s) at offset " + std::to_string(at_) +
                      ", the file has " + std::to_string(bytes_.size()));
  }
  uint8_t u8(const std::string& field) {
    need(1, field);
    return static_cast<uint8_t>(bytes_[at_++]);
  }
  uint32_t u32(const std::string& field) {
    need(4, field);
    uint32_t v = 0;
    for (int k = 0; k < 4; ++k) v |= static_cast<uint32_t>(static_cast<uint8_t>(bytes_[at_ + k])) << (8 * k);
    at_ += 4;
    return v;
  }
  float f32(const std::string& field) {
    const uint32_t v = u32(field);
    float f;
    std::memcpy(&f, &v, 4);
    return f;
  }
  size_t offset() const { return at_; }
  size_t remaining() const { return bytes_.size() - at_; }

 private:
  const std::string& bytes_;
  std::string context_;
  int frame_;
  size_t at_ = 0;
};
}  // namespace

fs::path bsp_border_file(const fs::path& root, const Resolution& resolution, int frame) {
  char name[32];
  std::snprintf(name, sizeof name, "%06d.bsp", frame);
  return root / resolution.name() / "bsp_border" / name;
}

std::string encode_bsp_border(const BspBorderImage& image) {
  std::string out(kMagic, sizeof kMagic);
  put_u32(out, kBspBorderFileVersion);
  put_u32(out, static_cast<uint32_t>(image.width()));
  put_u32(out, static_cast<uint32_t>(image.height()));
  put_u32(out, static_cast<uint32_t>(image.max_depth()));
  put_u32(out, static_cast<uint32_t>(image.size()));
  for (size_t k = 0; k < image.size(); ++k) {
    const BspTree& t = image.tree(k);
    put_u32(out, static_cast<uint32_t>(image.pixel(k)));
    out.push_back(static_cast<char>(t.lines.size()));
    put_u32(out, t.shape);
    for (const BspLine& l : t.lines) {
      put_f32(out, l.a);
      put_f32(out, l.b);
      put_f32(out, l.c);
    }
    for (const Rgb8& c : t.leaves) out.append(reinterpret_cast<const char*>(c.data()), 3);
  }
  return out;
}

BspBorderImage decode_bsp_border(const std::string& bytes, const std::string& context, int frame,
                                 const Resolution& expected) {
  Reader r(bytes, context, frame);
  r.need(kHeaderBytes, "header");
  if (std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    r.fail("header", "does not start with CGSRBSPB: not a sub-pixel BSP border file");
  for (size_t k = 0; k < sizeof kMagic; ++k) r.u8("header");
  const uint32_t version = r.u32("version");
  if (version != kBspBorderFileVersion)
    r.fail("version", "unsupported version " + std::to_string(version) + " (this build reads " +
                          std::to_string(kBspBorderFileVersion) + ")");
  const uint32_t width = r.u32("width"), height = r.u32("height");
  if (static_cast<int64_t>(width) != expected.width || static_cast<int64_t>(height) != expected.height)
    r.fail("width/height", "size " + std::to_string(width) + "x" + std::to_string(height) +
                               " does not match the resolution " + expected.name());
  const uint32_t max_depth = r.u32("max_depth");
  if (max_depth < 1 || max_depth > static_cast<uint32_t>(kMaxBspDepth))
    r.fail("max_depth", std::to_string(max_depth) + " is outside 1 .. " + std::to_string(kMaxBspDepth));
  const uint32_t count = r.u32("count");
  const uint64_t pixels = static_cast<uint64_t>(width) * height;
  if (count > pixels)
    r.fail("count", std::to_string(count) + " border pixels in an image of " + std::to_string(pixels) + " pixels");
  // The smallest record (one line) is 27 bytes: a huge count in a small file is caught before allocating.
  if (static_cast<uint64_t>(count) * 27 > r.remaining())
    r.fail("count", std::to_string(count) + " records cannot fit in the " + std::to_string(r.remaining()) +
                        " byte(s) after the header (truncated or corrupt)");
  const uint32_t max_lines = (1u << max_depth) - 1;
  BspBorderImage image(static_cast<int>(width), static_cast<int>(height), static_cast<int>(max_depth));
  int64_t previous = -1;
  for (uint32_t k = 0; k < count; ++k) {
    const std::string at = "record " + std::to_string(k);
    const uint32_t pixel = r.u32(at + " pixel");
    if (pixel >= pixels) r.fail(at + " pixel", std::to_string(pixel) + " is outside the image (" + std::to_string(pixels) + " pixels)");
    if (static_cast<int64_t>(pixel) <= previous)
      r.fail(at + " pixel", std::to_string(pixel) + " does not follow pixel " + std::to_string(previous) +
                                " (records must be in strictly ascending pixel order)");
    previous = pixel;
    const std::string here = at + " (pixel " + std::to_string(pixel) + ")";
    const uint32_t lines = r.u8(here + " line count");
    if (lines < 1 || lines > max_lines)
      r.fail(here + " line count", std::to_string(lines) + " is outside 1 .. " + std::to_string(max_lines) +
                                       " (max_depth " + std::to_string(max_depth) + ")");
    BspTree tree;
    tree.shape = r.u32(here + " shape");
    r.need(static_cast<size_t>(lines) * 12 + (lines + 1) * 3, here + " lines and leaves");
    tree.lines.resize(lines);
    for (auto& l : tree.lines) {
      l.a = r.f32(here + " line");
      l.b = r.f32(here + " line");
      l.c = r.f32(here + " line");
    }
    tree.leaves.resize(lines + 1);
    for (auto& c : tree.leaves)
      for (auto& v : c) v = r.u8(here + " leaf colour");
    if (const std::string p = tree.problem(); !p.empty()) r.fail(here, p);
    if (tree.depth() > static_cast<int>(max_depth))
      r.fail(here + " shape", "depth " + std::to_string(tree.depth()) + " exceeds max_depth " + std::to_string(max_depth));
    // Every line must cross the pixel: beyond half its diagonal from the centre it cannot.
    const double cx = pixel % width + 0.5, cy = pixel / width + 0.5;
    for (size_t i = 0; i < tree.lines.size(); ++i)
      if (std::abs(tree.lines[i].side(cx, cy)) > 0.7072)
        r.fail(here + " line " + std::to_string(i),
               "lies " + std::to_string(std::abs(tree.lines[i].side(cx, cy))) + " pixels from the pixel centre: it does not cross the pixel");
    image.add(static_cast<int>(pixel), std::move(tree));
  }
  if (r.remaining() != 0) r.fail("end", std::to_string(r.remaining()) + " trailing byte(s) after the last record");
  return image;
}

void write_bsp_border_file(const fs::path& path, const BspBorderImage& image) {
  fs::create_directories(path.parent_path());
  write_file_atomic(path, encode_bsp_border(image));
}

BspBorderImage read_bsp_border_file(const fs::path& path, int frame, const Resolution& expected) {
  if (!fs::exists(path))
    throw Error(path.string(), "frame " + std::to_string(frame) + ": missing sub-pixel BSP border file");
  return decode_bsp_border(read_file(path), path.string(), frame, expected);
}

}  // namespace cgsr
