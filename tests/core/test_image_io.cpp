// Image files <-> tensors: every supported encoding round-trips within its quantization step.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <filesystem>
#include <fstream>

#include "core/atomic_file.h"
#include "core/color.h"
#include "core/error.h"
#include "core/image_io.h"
#include "tests/support/scratch_dir.h"

using namespace cgsr;
namespace fs = std::filesystem;

namespace {
fs::path temp_dir() {
  static const fs::path dir = test::scratch_dir("image");
  return dir;
}

void expect_round_trip(const std::string& name, int bits, int channels, double tolerance) {
  torch::manual_seed(7);
  const auto image = torch::rand({channels, 9, 13});
  const auto path = temp_dir() / name;
  write_image(path, image, {bits});
  const auto back = read_image(path);
  ASSERT_EQ(back.sizes(), image.sizes()) << name;
  EXPECT_LE((back - image).abs().max().item<double>(), tolerance) << name;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(ImageIo, RoundTripsEveryEncoding) {
  expect_round_trip("c8.png", 8, 3, 0.5 / 255 + 1e-6);
  expect_round_trip("c16.png", 16, 3, 0.5 / 65535 + 1e-7);
  expect_round_trip("g16.png", 16, 1, 0.5 / 65535 + 1e-7);
  expect_round_trip("c8.ppm", 8, 3, 0.5 / 255 + 1e-6);
  expect_round_trip("c16.ppm", 16, 3, 0.5 / 65535 + 1e-7);
  expect_round_trip("c8.bmp", 8, 3, 0.5 / 255 + 1e-6);
  expect_round_trip("rgba8.png", 8, 4, 0.5 / 255 + 1e-6);
  expect_round_trip("f32.tif", 32, 3, 0.0);
  expect_round_trip("f32.exr", 32, 3, 0.0);
  expect_round_trip("g32.exr", 32, 1, 0.0);
}

TEST(ImageIo, FloatFormatsKeepValuesOutsideTheUnitRange) {
  const auto depth = torch::tensor({0.001f, 1.0f, 1e6f, 37.5f}).view({1, 2, 2});
  write_image(temp_dir() / "depth.exr", depth, {32});
  EXPECT_TRUE(torch::equal(read_image(temp_dir() / "depth.exr"), depth));
}

TEST(ImageIo, KeepsRgbOrder) {
  auto red = torch::zeros({3, 2, 2});
  red[0].fill_(1.0);
  write_image(temp_dir() / "red.png", red);
  const auto back = read_image(temp_dir() / "red.png");
  EXPECT_EQ(back[0].min().item<float>(), 1.0f);
  EXPECT_EQ(back[2].max().item<float>(), 0.0f);
}

TEST(ImageIo, IntegerEncodingsClampSaturatedValues) {
  const auto hot = torch::full({3, 2, 2}, 1.7f);
  write_image(temp_dir() / "hot.png", hot);
  EXPECT_EQ(read_image(temp_dir() / "hot.png").max().item<float>(), 1.0f);
}

TEST(ImageIo, ErrorsNameTheFileAndTheReason) {
  const auto missing = temp_dir() / "missing.png";
  EXPECT_NE(error_of([&] { read_image(missing); }).find("missing.png: no such image file"), std::string::npos);

  const auto corrupt = temp_dir() / "corrupt.png";
  write_file_atomic(corrupt, "\x89PNG this is not an image");
  EXPECT_NE(error_of([&] { read_image(corrupt); }).find("corrupt.png: unreadable image"), std::string::npos);

  write_image(temp_dir() / "grey.png", torch::rand({1, 4, 4}));
  EXPECT_NE(error_of([&] { read_image(temp_dir() / "grey.png", {3}); }).find("has 1 channel(s), expected 3"),
            std::string::npos);

  EXPECT_NE(error_of([&] { write_image(temp_dir() / "x.gif", torch::rand({3, 2, 2})); }).find("unsupported image format"),
            std::string::npos);
  EXPECT_NE(error_of([&] { write_image(temp_dir() / "x.bmp", torch::rand({3, 2, 2}), {16}); }).find("16-bit"),
            std::string::npos);
  auto nan = torch::rand({3, 2, 2});
  nan[1][1][1] = std::nanf("");
  EXPECT_NE(error_of([&] { write_image(temp_dir() / "nan.png", nan); }).find("NaN"), std::string::npos);
  EXPECT_FALSE(fs::exists(temp_dir() / "nan.png"));
}

TEST(Color, SrgbRoundTripAndKnownPoints) {
  const auto x = torch::linspace(0, 1, 101, torch::kFloat64);
  EXPECT_LT((linear_to_srgb(srgb_to_linear(x)) - x).abs().max().item<double>(), 1e-12);
  // sRGB 0.5 is 21.4% linear light.
  EXPECT_NEAR(srgb_to_linear(torch::tensor({0.5}, torch::kFloat64)).item<double>(), 0.214041, 1e-6);
}

TEST(Color, LumaOfWhiteAndBlack) {
  auto white = torch::ones({1, 3, 1, 1}, torch::kFloat64);
  EXPECT_NEAR(rgb_to_y(white).item<double>(), 235.0 / 255.0, 1e-4);
  EXPECT_NEAR(rgb_to_y(white * 0).item<double>(), 16.0 / 255.0, 1e-12);
}
