#pragma once
// Plots on a Canvas (Cairo; PNG, SVG or PDF by the file's extension): scatter plots of quality
// against cost for reports and search histories, line plots of a figure along a sequence (PSNR
// per frame, with the scene cuts), grouped bar charts with error bars for ablations. Every point
// label is placed where it overlaps no other text or marker and stays inside the plot; one that
// finds no such place is numbered and spelled out in the legend.

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "core/canvas.h"

namespace cgsr {

// "Nice" tick values covering [lo, hi]: multiples of 1, 2 or 5 times a power of ten. On a log axis
// lo and hi are log10 values and the ticks values: 1, 2 and 5 of each decade, or, where that gives
// fewer than three, every whole mantissa, or linear ticks of a range narrower still.
std::vector<double> axis_ticks(double lo, double hi, bool log_scale);

struct PlotPoint {
  double x = 0, y = 0;
  std::string label;  // drawn next to the point; "" for none
};

struct PlotSeries {
  std::string name;  // legend entry; "" for none
  Rgb colour{40, 90, 180};
  double radius = 5;
  bool connect = false;  // draw a polyline through the points (sorted by x)
  Marker marker = Marker::Circle;
  bool filled = true;
  std::vector<PlotPoint> points;
};

// A dashed line joining two points (say, a network and its control).
struct PlotLink {
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

struct ScatterPlot {
  std::string title, x_label, y_label;
  bool log_x = false;
  std::vector<PlotSeries> series;
  std::vector<std::pair<double, std::string>> horizontal_lines;  // y value and legend text
  std::vector<PlotLink> links;
  std::string links_name;          // legend entry of the links
  std::vector<std::string> notes;  // extra legend lines
};

// The drawn plot, for saving or for checking its layout. Throws cgsr::Error when there is
// nothing to draw.
std::unique_ptr<Canvas> draw_scatter_plot(const ScatterPlot& plot);
void write_scatter_plot(const std::filesystem::path& path, const ScatterPlot& plot);

// A line plot over an x axis cut into consecutive regions (say, the scenes of a frame sequence).
// Each series is drawn in segments: a segment is one polyline, and two segments are never joined
// (a scene cut, missing frames). A segment of one point is drawn as a dot. y = +inf is drawn on
// the top edge of the plot with a hollow marker (PSNR of identical images), -inf on the bottom
// edge; NaN points are left out. Every coordinate drawn is finite.
struct LineSeries {
  std::string name;  // legend entry
  Rgb colour{40, 90, 180};
  std::vector<std::vector<Point2>> segments;  // in data units, each in x order
  bool dots = false;  // a dot on every point as well (when the points are samples of the axis)
};

// A region of the x axis from `start` to the next region's start; every region but the first
// begins with a dashed vertical line. Region names are written at the top of the plot when there
// are several regions (a name that has no room is left out).
struct PlotRegion {
  double start = 0;
  std::string name;
};

struct LinePlot {
  std::string title, x_label, y_label;
  bool integer_x = false;  // ticks on whole numbers only (frame indices)
  std::vector<LineSeries> series;
  std::vector<PlotRegion> regions;  // in x order
  std::string boundary_name;        // legend entry of the region boundaries ("" = none)
  std::vector<std::string> notes;   // extra legend lines
};

// Throws cgsr::Error when there is no point to draw.
std::unique_ptr<Canvas> draw_line_plot(const LinePlot& plot);
void write_line_plot(const std::filesystem::path& path, const LinePlot& plot);

struct BarSeries {
  std::string name;  // legend entry
  Rgb colour{40, 90, 180};
  std::vector<double> values;     // one per category
  std::vector<double> low, high;  // error bar ends per category (empty: none)
};

// Groups of bars, one group per category, one bar per series; the zero line is drawn.
struct BarChart {
  std::string title, y_label;
  std::vector<std::string> categories;  // written under their group, reading upwards
  std::vector<BarSeries> series;
};

std::unique_ptr<Canvas> draw_bar_chart(const BarChart& chart);
void write_bar_chart(const std::filesystem::path& path, const BarChart& chart);

}  // namespace cgsr
