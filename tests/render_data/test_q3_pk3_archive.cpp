// The pk3 file system: zip archives through libzip, later archives override earlier ones,
// case-insensitive names, and errors that name the archive.
#include <gtest/gtest.h>

#include <fstream>

#include "core/error.h"
#include "render_data/q3/pk3_archive.h"
#include "tests/render_data/q3_test_map.h"

namespace cgsr::q3 {
namespace {

std::vector<uint8_t> bytes(const std::string& s) { return {s.begin(), s.end()}; }

TEST(Q3Pk3Archive, LaterArchivesOverrideEarlierOnesCaseInsensitively) {
  testing::TempDir dir;
  testing::write_pk3(dir.path() / "pak0.pk3", {{"textures/base/a.tga", bytes("old")}, {"maps/m.bsp", bytes("map")}});
  testing::write_pk3(dir.path() / "pak1.pk3", {{"Textures/Base/A.TGA", bytes("new")}});
  testing::write_pk3(dir.path() / "not_a_pk3.zip", {{"textures/base/a.tga", bytes("ignored")}});
  Pk3FileSystem files;
  EXPECT_EQ(files.add_directory(dir.path()), 2);
  EXPECT_EQ(files.archive_count(), 2u);
  EXPECT_EQ(files.read("textures/base/a.tga"), bytes("new"));
  EXPECT_EQ(files.read("TEXTURES\\BASE\\a.tga"), bytes("new"));
  EXPECT_EQ(files.read("maps/m.bsp"), bytes("map"));
  EXPECT_EQ(files.describe("textures/base/a.tga"), "pak1.pk3:Textures/Base/A.TGA");
  EXPECT_TRUE(files.contains("maps/M.bsp"));
  EXPECT_EQ(files.list("textures/", ".tga"), std::vector<std::string>{"textures/base/a.tga"});
  EXPECT_FALSE(files.try_read("textures/base/missing.tga").has_value());
}

TEST(Q3Pk3Archive, MissingFileNamesItAndTheArchiveCount) {
  testing::TempDir dir;
  testing::write_pk3(dir.path() / "pak0.pk3", {{"a.txt", bytes("a")}});
  Pk3FileSystem files;
  files.add_archive(dir.path() / "pak0.pk3");
  try {
    files.read("maps/none.bsp");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("maps/none.bsp"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("1 pk3"), std::string::npos);
  }
}

TEST(Q3Pk3Archive, CorruptArchivesAreErrorsNamingTheFile) {
  testing::TempDir dir;
  const auto garbage = dir.path() / "garbage.pk3";
  std::ofstream(garbage) << "this is not a zip archive at all";
  try {
    Pk3Archive archive(garbage);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("garbage.pk3"), std::string::npos);
  }

  // A valid archive cut in half: libzip cannot find the central directory.
  const auto whole = dir.path() / "whole.pk3";
  std::vector<uint8_t> payload(20000);
  for (size_t i = 0; i < payload.size(); ++i) payload[i] = static_cast<uint8_t>(i * 7);
  testing::write_pk3(whole, {{"data.bin", payload}});
  std::ifstream in(whole, std::ios::binary);
  std::string content((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto cut = dir.path() / "cut.pk3";
  std::ofstream(cut, std::ios::binary) << content.substr(0, content.size() / 2);
  EXPECT_THROW(Pk3Archive{cut}, Error);
  EXPECT_THROW(Pk3FileSystem().add_directory(dir.path() / "no_such_dir"), Error);
}

}  // namespace
}  // namespace cgsr::q3
