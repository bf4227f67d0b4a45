// Texture resolution across pk3 files (extension swapping as the game does) and decoding of TGA
// (stb_image, either row order) and JPG (OpenCV).
#include <gtest/gtest.h>

#include <tuple>

#include "core/error.h"
#include "render_data/q3/pk3_archive.h"
#include "render_data/q3/texture_resolver.h"
#include "tests/render_data/q3_test_map.h"

namespace cgsr::q3 {
namespace {

TEST(Q3TextureResolver, FindsImagesByStemAcrossArchives) {
  testing::TempDir dir;
  const auto map = testing::make_test_map();
  testing::write_pk3(dir.path() / "pak0.pk3", testing::test_map_files(map));
  testing::write_pk3(dir.path() / "pak1.pk3", {{"textures/extra/only.png", {1, 2, 3}}});
  Pk3FileSystem files;
  files.add_directory(dir.path());
  const TextureResolver resolver(files);
  EXPECT_EQ(resolver.find("textures/test/floor"), "textures/test/floor.tga");
  EXPECT_EQ(resolver.find("textures/test/floor.jpg"), "textures/test/floor.tga");  // swapped
  EXPECT_EQ(resolver.find("textures/test/wall.tga"), "textures/test/wall.jpg");
  EXPECT_EQ(resolver.find("Textures/Test/Wall"), "textures/test/wall.jpg");
  EXPECT_EQ(resolver.find("textures/extra/only"), "textures/extra/only.png");
  EXPECT_FALSE(resolver.find("textures/test/missing").has_value());
}

TEST(Q3TextureResolver, DecodesTgaInEitherRowOrderAndJpg) {
  // 2x2: red, green / blue, white (rows top to bottom).
  const std::vector<uint8_t> rgba = {255, 0, 0, 255, 0, 255, 0, 128, 0, 0, 255, 0, 255, 255, 255, 255};
  for (bool top_down : {false, true}) {
    const Texture t = decode_image(testing::encode_tga(2, 2, 4, rgba, top_down), "x.tga", true);
    ASSERT_EQ(t.width, 2);
    ASSERT_EQ(t.channels, 4);
    EXPECT_EQ(std::vector<uint8_t>(t.data.begin(), t.data.end()), rgba) << "top_down " << top_down;
    EXPECT_TRUE(t.srgb);
  }
  const Texture rgb = decode_image(testing::encode_tga(2, 2, 4, rgba, false), "x.tga", false);
  EXPECT_EQ(rgb.channels, 3);
  EXPECT_EQ(rgb.data[6], 0);  // blue pixel: r
  EXPECT_EQ(rgb.data[8], 255);

  const auto files = testing::test_map_files(testing::make_test_map());
  const Texture wall = decode_image(files.at("textures/test/wall.jpg"), "wall.jpg", false);
  ASSERT_EQ(wall.width, 8);
  EXPECT_NEAR(wall.data[0], 130, 2);  // written as BGR (90, 110, 130)
  EXPECT_NEAR(wall.data[1], 110, 2);
  EXPECT_NEAR(wall.data[2], 90, 2);
}

TEST(Q3TextureResolver, UndecodableImagesAreErrorsNamingTheFile) {
  for (const char* name : {"bad.tga", "bad.jpg"}) {
    try {
      decode_image({1, 2, 3, 4, 5, 6, 7, 8}, name, false);
      FAIL() << "expected an error for " << name;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos);
    }
  }
  EXPECT_THROW(decode_image({}, "empty.tga", false), Error);
}

// A texture declaring a huge size is refused from its header, naming the file, before a decoder
// allocates it: a TGA header alone declaring 65535x65535 (16 GiB of RGBA), and a PNG's IHDR
// declaring 20000x20000 with no pixel data after it.
TEST(Q3TextureResolver, HugeDeclaredSizesAreRefusedBeforeDecoding) {
  std::vector<uint8_t> tga = testing::encode_tga(1, 1, 3, {1, 2, 3}, false);
  tga[12] = tga[13] = tga[14] = tga[15] = 0xFF;  // width and height 65535
  const std::string ihdr("\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR\0\0\x4e\x20\0\0\x4e\x20\x08\x02\0\0\0\0\0\0\0", 33);
  const std::vector<uint8_t> png(ihdr.begin(), ihdr.end());
  for (const auto& [name, bytes, declared] :
       {std::tuple{"textures/x/bomb.tga", tga, "the TGA header declares 65535x65535 pixels"},
        std::tuple{"textures/x/bomb.png", png, "the PNG header declares 20000x20000 pixels"}}) {
    try {
      decode_image(bytes, name, false);
      FAIL() << "expected an error for " << name;
    } catch (const Error& e) {
      EXPECT_EQ(e.context(), name);
      EXPECT_NE(std::string(e.what()).find(declared), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("not decoded"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace cgsr::q3
