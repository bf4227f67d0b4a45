// Bar charts: a category's name gets the room it needs under the axis (the ablation's variant
// names run to 35 characters), and a series that does not match the categories is an error.
#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "core/error.h"
#include "core/plot.h"

using namespace cgsr;
namespace fs = std::filesystem;

namespace {
BarChart chart(const std::string& category) {
  BarChart c;
  c.title = "gain";
  c.categories = {"lr", category};
  c.series = {BarSeries{"overall", {40, 90, 180}, {0.01, -0.2}, {0.0, -0.3}, {0.02, -0.1}}};
  return c;
}

int height_of(const fs::path& png) {
  const cv::Mat img = cv::imread(png.string());
  EXPECT_FALSE(img.empty()) << png;
  return img.rows;
}
}  // namespace

TEST(BarChart, LongCategoryNamesGetTheRoomTheyNeed) {
  const fs::path dir = fs::temp_directory_path() / "cgsr-test-plot";
  fs::create_directories(dir);
  write_bar_chart(dir / "short.png", chart("hr_fuse"));
  write_bar_chart(dir / "long.png", chart("hr_unshuffle+hr_fuse - normal_angle (a long variant name)"));
  // The plot area is the same; the strip under it grows with the longest name.
  EXPECT_GT(height_of(dir / "long.png"), height_of(dir / "short.png") + 100);
  fs::remove_all(dir);
}

TEST(BarChart, ASeriesMustHaveOneValuePerCategory) {
  BarChart c = chart("hr_fuse");
  c.series[0].values.pop_back();
  EXPECT_THROW(write_bar_chart(fs::temp_directory_path() / "cgsr-test-plot-bad.png", c), Error);
}
