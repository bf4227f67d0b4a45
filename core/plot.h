#pragma once
// Plots as PNG (OpenCV drawing): scatter plots of quality against cost for reports and search
// histories, grouped bar charts with error bars for ablations.

#include <array>
#include <filesystem>
#include <string>
#include <vector>

namespace cgsr {

using Rgb = std::array<int, 3>;

struct PlotPoint {
  double x = 0, y = 0;
  std::string label;  // drawn next to the point; "" for none
};

struct PlotSeries {
  std::string name;  // legend entry
  Rgb colour{40, 90, 180};
  int radius = 5;
  bool connect = false;  // draw a polyline through the points (sorted by x)
  std::vector<PlotPoint> points;
};

struct ScatterPlot {
  std::string title, x_label, y_label;
  bool log_x = false;
  std::vector<PlotSeries> series;
  std::vector<std::pair<double, std::string>> horizontal_lines;  // y value and legend text
  std::vector<std::string> notes;                               // extra legend lines
};

// Throws cgsr::Error naming the path when there is nothing to draw.
void write_scatter_plot(const std::filesystem::path& path, const ScatterPlot& plot);

struct BarSeries {
  std::string name;  // legend entry
  Rgb colour{40, 90, 180};
  std::vector<double> values;     // one per category
  std::vector<double> low, high;  // error bar ends per category (empty: none)
};

// Groups of bars, one group per category, one bar per series; the zero line is drawn.
struct BarChart {
  std::string title, y_label;
  std::vector<std::string> categories;  // written under their group, turned when long
  std::vector<BarSeries> series;
};

void write_bar_chart(const std::filesystem::path& path, const BarChart& chart);

}  // namespace cgsr
