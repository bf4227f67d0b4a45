// Plots: a bar chart's category name gets the room it needs under the axis (the ablation's
// variant names run to 35 characters), a series that does not match the categories is an error,
// and no text of a plot overlaps another or leaves the canvas (the label test).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <tuple>
#include <opencv2/imgcodecs.hpp>

#include "core/error.h"
#include "core/plot.h"
#include "tests/support/scratch_dir.h"

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
  const fs::path dir = test::scratch_dir("plot");
  write_bar_chart(dir / "short.png", chart("hr_fuse"));
  write_bar_chart(dir / "long.png", chart("hr_unshuffle+hr_fuse - normal_angle (a long variant name)"));
  // The plot area is the same; the strip under it grows with the longest name.
  EXPECT_GT(height_of(dir / "long.png"), height_of(dir / "short.png") + 100);
  fs::remove_all(dir);
}

TEST(BarChart, ASeriesMustHaveOneValuePerCategory) {
  BarChart c = chart("hr_fuse");
  c.series[0].values.pop_back();
  EXPECT_THROW(write_bar_chart(test::scratch_dir("plot-bad") / "bad.png", c), Error);
}

namespace {
// Every text inside the canvas and clear of every other text.
void expect_readable(const Canvas& canvas, const std::string& what) {
  const auto& boxes = canvas.text_boxes();
  ASSERT_FALSE(boxes.empty()) << what;
  for (size_t i = 0; i < boxes.size(); ++i) {
    EXPECT_TRUE(boxes[i].inside(canvas.bounds())) << what << ": text " << i << " leaves the canvas";
    for (size_t j = i + 1; j < boxes.size(); ++j)
      EXPECT_FALSE(boxes[i].overlaps(boxes[j])) << what << ": texts " << i << " and " << j << " overlap";
  }
}
}  // namespace

// The quickstart's crowded corner: nine networks within 0.5 dB and a factor 3 of latency, two
// pairs of them on the same spot, plus frames that chose the same pattern at the same density.
TEST(ScatterPlot, LabelsNeverOverlapOrLeaveTheCanvas) {
  ScatterPlot plot;
  plot.title = "varied_indoor x2: PSNR against latency";
  plot.x_label = "latency (ms, median, log scale)";
  plot.y_label = "PSNR (dB)";
  plot.log_x = true;
  PlotSeries networks{"network", {40, 90, 180}, 5, false, Marker::Circle, true, {}};
  const std::vector<std::tuple<double, double, std::string>> rows = {
      {374.3, 25.43, "PAN x2"}, {374.4, 25.46, "PAN x2 (control)"}, {394.2, 25.49, "CG-enhanced PAN x2"},
      {390.5, 25.48, "elastic CG-enhanced PAN x2"}, {122.9, 25.55, "CG-optimized PAN x2 (scratch)"},
      {127.2, 25.15, "CG-enhanced PAN x2 MMP"}, {128.9, 25.43, "CG-enhanced PAN x2 uniform width"},
      {121.8, 25.44, "CG-optimized PAN x2"}, {242.6, 25.45, "CG-optimized PAN x2 static"},
      {182.5, 25.26, "CG-optimized PAN x2 hybrid"}, {2.84, 24.40, "bicubic"}, {0.63, 23.77, "bilinear"},
      {121.8, 25.44, "the same spot"}, {121.8, 25.44, "and once more"}};
  for (const auto& [x, y, name] : rows) networks.points.push_back({x, y, name});
  plot.series = {networks};
  plot.links = {{394.2, 25.49, 374.4, 25.46}};
  plot.links_name = "a network and its control";
  plot.horizontal_lines = {{25.0, "fsr (no latency)"}};
  const auto canvas = draw_scatter_plot(plot);
  expect_readable(*canvas, "report plot");

  ScatterPlot choices;
  choices.title = "CG-optimized PAN x2 hybrid: pattern chosen per frame";
  choices.x_label = "geometry-edge pixels of the frame (%)";
  choices.y_label = "channels the chosen pattern keeps (%)";
  PlotSeries frames{"pattern 0 (40 frames)", {220, 40, 40}, 5, false, Marker::Circle, true, {}};
  for (int f = 0; f < 40; ++f) frames.points.push_back({7.0 + 0.01 * (f % 5), 100.0, std::to_string(f)});
  choices.series = {frames};
  expect_readable(*draw_scatter_plot(choices), "pattern choice plot");
}

// Scenes close together with long names: the names that have no room are left out, none overlaps.
TEST(LinePlot, LabelsNeverOverlapOrLeaveTheCanvas) {
  LinePlot plot;
  plot.title = "corridors x2: PSNR per frame";
  plot.x_label = "frame (index in the data set)";
  plot.y_label = "PSNR (dB)";
  plot.integer_x = true;
  for (int scene = 0; scene < 12; ++scene)
    plot.regions.push_back({scene * 40.0, "a long scene name " + std::to_string(scene)});
  plot.boundary_name = "scene cut (the history starts again)";
  plot.notes = {"hollow on the top edge: PSNR +inf (identical)"};
  for (const std::string name : {"bicubic", "CG-optimized PAN x2 hybrid"}) {
    LineSeries s{name, {40, 90, 180}, {}, false};
    for (int scene = 0; scene < 12; ++scene) {
      s.segments.emplace_back();
      for (int f = scene * 40; f < scene * 40 + 40; ++f) s.segments.back().push_back({double(f), 25 + (f % 7) * 0.3});
    }
    s.segments.back().back().y = INFINITY;
    plot.series.push_back(s);
  }
  const auto canvas = draw_line_plot(plot);
  expect_readable(*canvas, "line plot");
  EXPECT_GT(canvas->text_boxes().size(), 12u);  // some scene names were written

  LinePlot empty = plot;
  for (auto& s : empty.series) s.segments = {{{NAN, 3.0}}};
  EXPECT_THROW(draw_line_plot(empty), Error);
}

TEST(AxisTicks, ALogAxisShowsSeveralTicksHoweverNarrow) {
  const auto log_ticks = [](double lo, double hi) { return axis_ticks(std::log10(lo), std::log10(hi), true); };
  EXPECT_EQ(log_ticks(0.6, 450), (std::vector<double>{1, 2, 5, 10, 20, 50, 100, 200}));
  EXPECT_EQ(log_ticks(110, 420), (std::vector<double>{200, 300, 400}));  // 1-2-5 would give 200 alone
  const auto narrow = log_ticks(121.5, 124.5);
  ASSERT_GE(narrow.size(), 2u);
  for (double v : narrow) EXPECT_TRUE(v >= 121.5 && v <= 124.5) << v;
  EXPECT_EQ(axis_ticks(-0.3, 1.1, false), (std::vector<double>{0, 0.5, 1}));
}

TEST(BarChart, LabelsNeverOverlapOrLeaveTheCanvas) {
  BarChart c = chart("hr_unshuffle+hr_fuse - normal_angle (a long variant name)");
  c.title = "a title longer than the chart's few bars would make room for";
  expect_readable(*draw_bar_chart(c), "bar chart");
}

TEST(Canvas, SavesPngSvgAndPdfByExtension) {
  const fs::path dir = test::scratch_dir("canvas");
  Canvas c(120, 80);
  c.text({10, 40}, "PSNR 25.4 dB", {});
  c.marker({100, 40}, Marker::Diamond, 5, {220, 40, 40}, true);
  c.save(dir / "c.png");
  c.save(dir / "c.svg");
  c.save(dir / "c.pdf");
  const cv::Mat png = cv::imread((dir / "c.png").string());
  EXPECT_EQ(png.cols, 120);
  EXPECT_EQ(png.rows, 80);
  EXPECT_LT(cv::mean(png)[0], 254.0);  // something was drawn on the white
  std::ifstream svg(dir / "c.svg"), pdf(dir / "c.pdf");
  const std::string svg_text((std::istreambuf_iterator<char>(svg)), {}), pdf_text((std::istreambuf_iterator<char>(pdf)), {});
  EXPECT_NE(svg_text.find("<svg"), std::string::npos);
  EXPECT_EQ(pdf_text.substr(0, 5), "%PDF-");
  EXPECT_THROW(c.save(dir / "c.jpg"), Error);
  fs::remove_all(dir);
}
