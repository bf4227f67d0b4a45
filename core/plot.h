#pragma once
// Scatter plots as PNG (OpenCV drawing): quality against cost for reports and search histories.

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

}  // namespace cgsr
