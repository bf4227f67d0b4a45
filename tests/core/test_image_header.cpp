// Image headers read without decoding: the size of every format cgsr reads, and the checks made
// with it before a decoder allocates what a header declares (a decompression bomb).
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <filesystem>
#include <tuple>
#include <opencv2/imgcodecs.hpp>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_header.h"
#include "core/image_io.h"
#include "tests/support/scratch_dir.h"

using namespace cgsr;
namespace fs = std::filesystem;

namespace {
fs::path header_dir() {
  static const fs::path dir = test::scratch_dir("image-header");
  return dir;
}

// The bomb seed of fuzz_frame_files (fuzz/make_seeds.sh): a valid PNG of about 1 KB that declares
// 20000x20000 RGB pixels and holds 16 rows of them; the seed's first byte is the file kind.
std::string png_bomb() {
  const std::string seed = read_file(fs::path(CGSR_SOURCE_DIR) / "fuzz/corpus/frame_files/color_bomb_20000x20000.bin");
  return seed.substr(1);
}

std::string header_error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::User) << e.what();
    return e.what();
  }
  return "no error";
}
}  // namespace

TEST(ImageHeader, ReadsTheSizeOfEveryFormatCgsrReads) {
  const auto image = torch::rand({3, 9, 13});
  for (const std::string name : {"a.png", "a.ppm", "a.bmp", "a.tif", "a.exr"}) {
    write_image(header_dir() / name, image, {name == "a.tif" || name == "a.exr" ? 32 : 8});
    const ImageHeader h = read_image_header(header_dir() / name);
    EXPECT_EQ(h.width, 13) << name;
    EXPECT_EQ(h.height, 9) << name;
  }
  write_image(header_dir() / "g.pgm", torch::rand({1, 5, 7}));
  EXPECT_EQ(read_image_header(header_dir() / "g.pgm").width, 7);
  // JPEG (read, never written by cgsr): the size sits in the frame header after the metadata.
  std::vector<unsigned char> jpeg;
  ASSERT_TRUE(cv::imencode(".jpg", cv::Mat(21, 34, CV_8UC3, cv::Scalar(1, 2, 3)), jpeg));
  const ImageHeader h = parse_image_header(std::string(jpeg.begin(), jpeg.end()), "a.jpg");
  EXPECT_EQ(h.format, "JPEG");
  EXPECT_EQ(h.width, 34);
  EXPECT_EQ(h.height, 21);
}

TEST(ImageHeader, CutShortAndUnknownHeadersAreErrorsNamingTheFile) {
  EXPECT_NE(header_error_of([] { parse_image_header(std::string("\x89PNG\r\n\x1a\n\0\0", 10), "x.png"); })
                .find("x.png: unreadable image: the image header is cut short"),
            std::string::npos);
  EXPECT_NE(header_error_of([] { parse_image_header("GIF89a....", "x.gif"); }).find("x.gif: unreadable image: not a format"),
            std::string::npos);
  EXPECT_NE(header_error_of([] { parse_image_header("P6\n# only a comment\n", "x.ppm"); }).find("x.ppm: unreadable image"),
            std::string::npos);
}

// The bomb: ~1 KB on disk, 20000x20000 declared, placed where a 64x48 frame belongs.
// It used to be decoded in full (2.5 GB) before its size was checked.
TEST(ImageHeader, ADecompressionBombIsRefusedBeforeDecoding) {
  const fs::path bomb = header_dir() / "bomb.png";
  write_file_atomic(bomb, png_bomb());
  ASSERT_LT(fs::file_size(bomb), 4096u);
  EXPECT_EQ(read_image_header(bomb).width, 20000);
  std::string e = header_error_of([&] { read_image(bomb, {3, 64, 48}); });
  EXPECT_NE(e.find(bomb.string() + ": size 20000x20000 (from the PNG header; not decoded) does not match the "
                                   "resolution 64x48"),
            std::string::npos)
      << e;
  // Of unknown size, it is held to the limits.
  e = header_error_of([&] { read_image(bomb); });
  EXPECT_NE(e.find("declares 20000x20000 pixels, beyond the limit of 16384 a side"), std::string::npos) << e;
  // Within the limits but not the frame's size.
  const fs::path large = header_dir() / "large.png";
  write_image(large, torch::rand({3, 480, 640}));
  e = header_error_of([&] { read_image(large, {3, 64, 48}); });
  EXPECT_NE(e.find("size 640x480 (from the PNG header; not decoded) does not match the resolution 64x48"),
            std::string::npos)
      << e;
  EXPECT_EQ(read_image(large, {3, 640, 480}).size(2), 640);
}

// fuzz_frame_files' bombs in each format a frame file can reach (fuzz/make_bomb_seeds.py): a JPEG
// of 157 bytes and an EXR of 11 KB declare 20000x20000 as the PNG does, each refused from its header.
TEST(ImageHeader, EveryBombSeedIsRefusedFromItsHeader) {
  for (const auto& [seed, format, extension] :
       {std::tuple{"color_bomb_20000x20000.bin", "PNG", ".png"}, std::tuple{"color_jpeg_bomb_20000x20000.bin", "JPEG", ".png"},
        std::tuple{"depth_bomb_20000x20000.bin", "EXR", ".exr"}}) {
    const std::string bytes = read_file(fs::path(CGSR_SOURCE_DIR) / "fuzz/corpus/frame_files" / seed).substr(1);
    const fs::path bomb = header_dir() / (std::string(seed) + extension);
    write_file_atomic(bomb, bytes);
    EXPECT_LT(fs::file_size(bomb), 16384u) << seed;
    const std::string e = header_error_of([&] { read_image(bomb); });
    EXPECT_NE(e.find(std::string("the ") + format + " header declares 20000x20000 pixels"), std::string::npos) << e;
  }
}

// An OpenEXR header is walked as OpenEXR reads it. The first 10-minute fuzz_frame_files run found
// a file (the seed depth_exr_header_walk.bin) whose channel list declared fewer bytes than its
// channels take: skipping by the size field, the check saw a valid header, while OpenEXR read on
// from the channels' end into a made-up attribute of 1.85 GB and allocated it. Every attribute's
// size is now checked against what OpenEXR reads for its type.
TEST(ImageHeader, AnOpenExrHeaderIsReadAsOpenExrReadsIt) {
  const std::string found = read_file(fs::path(CGSR_SOURCE_DIR) / "fuzz/corpus/frame_files/depth_exr_header_walk.bin");
  EXPECT_NE(header_error_of([&] { parse_image_header(found.substr(1), "walk.exr"); }).find("walk.exr: unreadable image: "
                                                                                         "an OpenEXR"),
            std::string::npos);
  // A frame cgsr writes passes; the same with a fixed-size attribute resized, a channel list
  // that disagrees with its size, an overlong name, a preview or the multi-part flag does not.
  write_image(header_dir() / "walk.exr", torch::rand({3, 9, 13}), {32});
  const std::string exr = read_file(header_dir() / "walk.exr");
  EXPECT_EQ(parse_image_header(exr, "walk.exr").width, 13);
  const auto refused = [&](std::string bytes, const std::string& why) {
    const std::string e = header_error_of([&] { parse_image_header(bytes, "walk.exr"); });
    EXPECT_NE(e.find(why), std::string::npos) << e;
  };
  const auto size_of = [&](const std::string& attribute) { return exr.find(attribute) + attribute.size(); };
  std::string resized = exr;
  resized[size_of(std::string("compression\0compression\0", 24))] = 2;
  refused(resized, "'compression' attribute of 2 bytes, not 1");
  std::string channels = exr;
  channels[size_of(std::string("channels\0chlist\0", 16))] -= 1;
  refused(channels, "channel list whose size disagrees");
  std::string named = exr;
  named.insert(8, std::string(300, 'n') + std::string("\0int\0\4\0\0\0\0\0\0\0", 13));
  refused(named, "attribute name longer than 255 bytes");
  std::string preview = exr;
  preview.insert(8, std::string("p\0preview\0\0\0\0\0", 14));
  refused(preview, "'preview' attribute");
  std::string parts = exr;
  parts[5] |= 0x10;
  refused(parts, "deep or multi-part");
}

// A size given twice in a header is refused: decoders take one or the other (OpenEXR the last
// dataWindow, libtiff the first width tag), so a small size beside a huge one would pass the
// check and be decoded huge.
TEST(ImageHeader, ASizeGivenTwiceIsRefused) {
  const auto image = torch::rand({3, 9, 13});
  write_image(header_dir() / "twice.exr", image, {32});
  std::string exr = read_file(header_dir() / "twice.exr");
  const std::string attribute = std::string("dataWindow\0box2i\0", 17);
  const size_t at = exr.find(attribute);
  ASSERT_NE(at, std::string::npos);
  std::string huge = exr.substr(at, attribute.size() + 4 + 8) + std::string("\x1f\x4e\0\0\x1f\x4e\0\0", 8);  // 19999
  exr.insert(at + attribute.size() + 4 + 16, huge);
  EXPECT_NE(header_error_of([&] { parse_image_header(exr, "twice.exr"); }).find("twice.exr: unreadable image: an OpenEXR "
                                                                               "header with two dataWindows"),
            std::string::npos);

  write_image(header_dir() / "twice.tif", image, {8});
  std::string tiff = read_file(header_dir() / "twice.tif");
  ASSERT_EQ(tiff.substr(0, 2), "II");
  const auto u16 = [&](size_t k) { return static_cast<uint32_t>(uint8_t(tiff[k]) | uint8_t(tiff[k + 1]) << 8); };
  const size_t ifd = u16(4) | u16(6) << 16;
  for (uint32_t i = 0; i < u16(ifd); ++i) {
    const size_t e = ifd + 2 + 12 * i;
    if (u16(e) == 257) tiff[e] = 0;  // the height tag becomes a second width tag (256 = 0x100)
  }
  EXPECT_NE(header_error_of([&] { parse_image_header(tiff, "twice.tif"); }).find("a TIFF file with its width or height "
                                                                                "tag twice"),
            std::string::npos);
}
