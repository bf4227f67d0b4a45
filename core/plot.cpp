#include "core/plot.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <tuple>

#include "core/error.h"

namespace cgsr {

std::vector<double> axis_ticks(double lo, double hi, bool log_scale) {
  std::vector<double> out;
  if (log_scale) {
    // A latency axis often spans less than a decade (the networks of a report: 110-420 ms), where
    // 1-2-5 leaves a single tick.
    for (const std::vector<int>& mantissas : {std::vector<int>{1, 2, 5}, std::vector<int>{1, 2, 3, 4, 5, 6, 7, 8, 9}}) {
      out.clear();
      for (int e = static_cast<int>(std::floor(lo)); e <= static_cast<int>(std::ceil(hi)); ++e)
        for (int m : mantissas) {
          const double v = m * std::pow(10.0, e);
          if (std::log10(v) >= lo && std::log10(v) <= hi) out.push_back(v);
        }
      if (out.size() >= 3) return out;
    }
    return axis_ticks(std::pow(10.0, lo), std::pow(10.0, hi), false);
  }
  const double raw = (hi - lo) / 5.0;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  double step = magnitude;
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (raw <= m * magnitude) {
      step = m * magnitude;
      break;
    }
  // Multiples of the step, so that 0 is exactly 0 (not the residue of repeated additions).
  // + 0.0 turns -0 (from ceil of a small negative) into 0, which prints without a sign.
  for (double k = std::ceil(lo / step); k * step <= hi + 1e-12; k += 1) out.push_back(k * step + 0.0);
  return out;
}

namespace {
const TextStyle kTitle{16, true}, kAxis{13}, kTick{11, false, {70, 70, 70}}, kLabel{11}, kLegend{12};
constexpr double kLabelGap = 4;  // pixels between a point label and any other text or marker
const Rgb kBlack{0, 0, 0}, kGrid{225, 225, 225}, kFrame{60, 60, 60}, kLeader{150, 150, 150}, kLink{70, 70, 70};

std::string tick_text(double v) {
  std::ostringstream s;
  s.precision(v != 0 && std::abs(v) < 1 ? 2 : 4);
  s << v;
  return s.str();
}

std::pair<double, double> padded(double lo, double hi) {
  const double margin = hi > lo ? 0.08 * (hi - lo) : 0.5;
  return {lo - margin, hi + margin};
}

bool collides(const Box& box, const std::vector<Box>& taken) {
  return std::any_of(taken.begin(), taken.end(), [&](const Box& t) { return box.overlaps(t); });
}

// Draws a tick label unless it would overlap one already drawn (dense ticks thin out).
void tick_label(Canvas& canvas, Point2 at, const std::string& text, Anchor anchor) {
  const Box box = canvas.measure(text, kTick, at, anchor).grown(2);
  if (box.inside(canvas.bounds()) && !collides(box, canvas.text_boxes())) canvas.text(at, text, kTick, anchor);
}

// Where a label of `size` may go around a marker of radius `r` at `p`: first right next to it
// (east, west, the diagonals, north, south), then on rings further out, joined by a leader line.
std::vector<Box> label_candidates(Point2 p, double r, const Box& size) {
  const double w = size.width(), h = size.height(), d = r * 1.3 + 2 + kLabelGap;  // clear of the marker's box
  std::vector<Box> out = {
      {p.x + d, p.y - h / 2, p.x + d + w, p.y + h / 2},          {p.x - d - w, p.y - h / 2, p.x - d, p.y + h / 2},
      {p.x + d * 0.7, p.y - d * 0.7 - h, p.x + d * 0.7 + w, p.y - d * 0.7},
      {p.x - d * 0.7 - w, p.y - d * 0.7 - h, p.x - d * 0.7, p.y - d * 0.7},
      {p.x + d * 0.7, p.y + d * 0.7, p.x + d * 0.7 + w, p.y + d * 0.7 + h},
      {p.x - d * 0.7 - w, p.y + d * 0.7, p.x - d * 0.7, p.y + d * 0.7 + h},
      {p.x - w / 2, p.y - d - h, p.x + w / 2, p.y - d},          {p.x - w / 2, p.y + d, p.x + w / 2, p.y + d + h}};
  for (int ring = 1; ring <= 10; ++ring)
    for (int k = 0; k < 16; ++k) {
      const double a = k * M_PI / 8, dist = d + 14.0 * ring;
      const double cx = p.x + std::cos(a) * (dist + w / 2), cy = p.y - std::sin(a) * (dist + h / 2);
      out.push_back({cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2});
    }
  return out;
}

// The point of `box` nearest to `p` (where a leader line ends).
Point2 nearest_on(const Box& box, Point2 p) {
  return {std::clamp(p.x, box.x0, box.x1), std::clamp(p.y, box.y0, box.y1)};
}

// The plot area and its axes: the margins hold the tick labels and the axis titles, the area
// is plot_w x plot_h pixels, and px/py map data to canvas pixels. Shared by the scatter and
// line plots; the caller sizes the canvas from its legend (canvas_size) and draws the axes.
struct Axes {
  Box area;
  double x_lo = 0, x_hi = 1, y_lo = 0, y_hi = 1;  // padded; log10 values on a log axis
  bool log_x = false;
  std::vector<double> x_ticks, y_ticks;
  double line_height = 0;  // of a legend line

  double px(double x) const {
    const double v = log_x ? std::log10(std::max(x, 1e-12)) : x;
    return area.x0 + (v - x_lo) / (x_hi - x_lo) * area.width();
  }
  double py(double y) const { return area.y1 - (y - y_lo) / (y_hi - y_lo) * area.height(); }
  double bottom_margin() const {
    Canvas probe(1, 1);
    return 8 + probe.measure("Ag", kTick).height() + 10 + probe.measure("Ag", kAxis).height() + 14;
  }
  // The canvas: the area and its margins, the legend column right of it (`legend_width` wide,
  // `legend_lines` lines, next to a 30 px sample), and as tall as the taller of the two.
  std::pair<int, int> canvas_size(double legend_width, size_t legend_lines) const {
    const double height = std::max(area.y1 + bottom_margin(), area.y0 + 10 + line_height * legend_lines + 10);
    const double width = area.x1 + 24 + 30 + legend_width + 16;
    return {static_cast<int>(std::ceil(width)), static_cast<int>(std::ceil(height))};
  }
};

// `xs` (log10 values on a log axis) and `ys` must not be empty; `x_margin` is the share of the
// x range left free at each end.
Axes layout_axes(const std::vector<double>& xs, const std::vector<double>& ys, bool log_x, double plot_w,
                 double plot_h, double x_margin = 0.08) {
  Axes a;
  a.log_x = log_x;
  const double x_min = *std::min_element(xs.begin(), xs.end()), x_max = *std::max_element(xs.begin(), xs.end());
  const double x_pad = x_max > x_min ? x_margin * (x_max - x_min) : 0.5;
  a.x_lo = x_min - x_pad;
  a.x_hi = x_max + x_pad;
  std::tie(a.y_lo, a.y_hi) = padded(*std::min_element(ys.begin(), ys.end()), *std::max_element(ys.begin(), ys.end()));
  a.x_ticks = axis_ticks(a.x_lo, a.x_hi, log_x);
  a.y_ticks = axis_ticks(a.y_lo, a.y_hi, false);
  Canvas probe(1, 1);
  double y_tick_width = 0;
  for (double v : a.y_ticks) y_tick_width = std::max(y_tick_width, probe.measure(tick_text(v), kTick).width());
  a.line_height = probe.measure("Ag", kLegend).height() + 5;
  const double left = 14 + probe.measure("Ag", kAxis).height() + 10 + y_tick_width + 8;
  const double top = 16 + probe.measure("Ag", kTitle).height() + 14;
  a.area = {left, top, left + plot_w, top + plot_h};
  return a;
}

// Title, axis titles, grid, tick labels and the frame round the area.
void draw_axes(Canvas& c, const Axes& a, const std::string& title, const std::string& x_label,
               const std::string& y_label) {
  Canvas probe(1, 1);
  const double tick_height = probe.measure("Ag", kTick).height();
  c.text({a.area.x0 + a.area.width() / 2, 16 + probe.measure("Ag", kTitle).height() - 4}, title, kTitle,
         Anchor::Centre);
  c.vertical_text({14 + probe.measure("Ag", kAxis).height() / 2, a.area.y0 + a.area.height() / 2}, y_label, kAxis);
  c.text({a.area.x0 + a.area.width() / 2, c.height() - 12.0}, x_label, kAxis, Anchor::Centre);
  for (double v : a.x_ticks) {
    c.line({a.px(v), a.area.y0}, {a.px(v), a.area.y1}, kGrid);
    tick_label(c, {a.px(v), a.area.y1 + 8 + tick_height - 3}, tick_text(v), Anchor::Centre);
  }
  for (double v : a.y_ticks) {
    c.line({a.area.x0, a.py(v)}, {a.area.x1, a.py(v)}, kGrid);
    tick_label(c, {a.area.x0 - 6, a.py(v) + 4}, tick_text(v), Anchor::Right);
  }
  c.rectangle(a.area, kFrame, false);
}

// The legend column right of the area: each entry a 22 px sample (drawn by the caller at
// sample()) and its text.
struct Legend {
  Canvas& c;
  double x, y, line_height;
  Legend(Canvas& canvas, const Axes& a) : c(canvas), x(a.area.x1 + 24), y(a.area.y0 + 10 + a.line_height / 2),
                                          line_height(a.line_height) {}
  Point2 sample_start() const { return {x, y}; }
  Point2 sample_end() const { return {x + 22, y}; }
  Point2 sample_centre() const { return {x + 11, y}; }
  void text(const std::string& t) {
    c.text({x + 30, y + 4}, t, kLegend);
    y += line_height;
  }
};

struct PlacedLabel {
  std::string text;
  Point2 at;    // the marker
  Box box;      // where the text goes
  bool leader;  // away from the marker: a line joins them
};
}  // namespace

std::unique_ptr<Canvas> draw_scatter_plot(const ScatterPlot& plot) {
  std::vector<double> xs, ys;
  for (const auto& s : plot.series)
    for (const auto& p : s.points) {
      if (plot.log_x && p.x <= 0) continue;
      xs.push_back(plot.log_x ? std::log10(p.x) : p.x);
      ys.push_back(p.y);
    }
  for (const auto& [y, text] : plot.horizontal_lines) ys.push_back(y);
  if (ys.empty()) throw Error("plot '" + plot.title + "'", "nothing to plot");
  if (xs.empty()) xs = {0.0, 1.0};
  const Axes axes = layout_axes(xs, ys, plot.log_x, 640, 460);
  const Box& area = axes.area;
  auto px = [&](double x) { return axes.px(x); };
  auto py = [&](double y) { return axes.py(y); };

  // The legend column from its longest entry.
  Canvas probe(1, 1);
  std::vector<std::string> legend_texts;
  for (const auto& [y, text] : plot.horizontal_lines) legend_texts.push_back(text);
  for (const auto& s : plot.series)
    if (!s.name.empty()) legend_texts.push_back(s.name);
  if (!plot.links.empty() && !plot.links_name.empty()) legend_texts.push_back(plot.links_name);
  double legend_width = 0;
  for (const auto& t : legend_texts) legend_width = std::max(legend_width, probe.measure(t, kLegend).width());
  for (const auto& t : plot.notes) legend_width = std::max(legend_width, probe.measure(t, kLegend).width());

  // Every point label, placed before anything is drawn: the ones with no free place become
  // numbers, spelled out in the legend, which may then need more height.
  std::vector<Box> taken;  // markers, then labels as they are placed
  for (const auto& s : plot.series)
    for (const auto& p : s.points)
      if (!(plot.log_x && p.x <= 0))
        taken.push_back(Box{px(p.x), py(p.y), px(p.x), py(p.y)}.grown(s.radius * 1.3 + 1));
  const Box inner = area.grown(-3);
  std::vector<PlacedLabel> placed;
  std::vector<std::string> numbered;
  auto place = [&](const std::string& text, Point2 at, double radius) {
    const Box size = probe.measure(text, kLabel);
    const auto candidates = label_candidates(at, radius, size);
    for (size_t c = 0; c < candidates.size(); ++c)
      if (candidates[c].inside(inner) && !collides(candidates[c].grown(kLabelGap), taken)) {
        taken.push_back(candidates[c]);
        placed.push_back({text, at, candidates[c], c >= 8});
        return true;
      }
    return false;
  };
  for (const auto& s : plot.series)
    for (const auto& p : s.points) {
      if (p.label.empty() || (plot.log_x && p.x <= 0)) continue;
      const Point2 at{px(p.x), py(p.y)};
      if (place(p.label, at, s.radius)) continue;
      const std::string number = std::to_string(numbered.size() + 1);
      numbered.push_back(number + ": " + p.label);
      if (!place(number, at, s.radius)) numbered.back() += " (not marked: no room)";
    }
  for (const auto& n : numbered) legend_width = std::max(legend_width, probe.measure(n, kLegend).width());

  const size_t legend_lines = legend_texts.size() + plot.notes.size() + numbered.size();
  const auto [width, height] = axes.canvas_size(legend_width, legend_lines);
  auto canvas = std::make_unique<Canvas>(width, height);
  Canvas& c = *canvas;
  draw_axes(c, axes, plot.title, plot.x_label, plot.y_label);

  // The legend, right of the plot: a sample of each series' line or marker, then the notes.
  Legend legend(c, axes);
  for (const auto& [y, text] : plot.horizontal_lines) {
    c.line({area.x0, py(y)}, {area.x1, py(y)}, {120, 120, 120}, 1, true);
    c.line(legend.sample_start(), legend.sample_end(), {120, 120, 120}, 1, true);
    legend.text(text);
  }
  for (const auto& s : plot.series) {
    if (s.connect && s.points.size() > 1) {
      auto sorted = s.points;
      std::sort(sorted.begin(), sorted.end(), [](const PlotPoint& a, const PlotPoint& b) { return a.x < b.x; });
      std::vector<Point2> line;
      for (const auto& p : sorted)
        if (!(plot.log_x && p.x <= 0)) line.push_back({px(p.x), py(p.y)});
      c.polyline(line, s.colour, 1.5);
    }
    if (s.name.empty()) continue;
    if (s.connect) c.line(legend.sample_start(), legend.sample_end(), s.colour, 1.5);
    c.marker(legend.sample_centre(), s.marker, std::min(s.radius, 6.0), s.colour, s.filled);
    legend.text(s.name);
  }
  if (!plot.links.empty() && !plot.links_name.empty()) {
    c.line(legend.sample_start(), legend.sample_end(), kLink, 1.6, true);
    legend.text(plot.links_name);
  }
  for (const auto& note : plot.notes) legend.text(note);
  for (const auto& n : numbered) legend.text(n);

  // Links over the series' lines (a pair often lies along the Pareto front), under the markers.
  for (const auto& link : plot.links) c.line({px(link.x0), py(link.y0)}, {px(link.x1), py(link.y1)}, kLink, 1.6, true);
  for (const auto& s : plot.series)
    for (const auto& p : s.points)
      if (!(plot.log_x && p.x <= 0)) c.marker({px(p.x), py(p.y)}, s.marker, s.radius, s.colour, s.filled);
  for (const auto& l : placed) {
    if (l.leader) c.line(l.at, nearest_on(l.box, l.at), kLeader, 0.8);
    c.text({l.box.x0, l.box.y1 - probe.measure(l.text, kLabel).y1}, l.text, kLabel);
  }
  return canvas;
}

void write_scatter_plot(const std::filesystem::path& path, const ScatterPlot& plot) {
  draw_scatter_plot(plot)->save(path);
}

std::unique_ptr<Canvas> draw_line_plot(const LinePlot& plot) {
  // The axes cover the finite points; infinite y values sit on an edge, so do not stretch them.
  std::vector<double> xs, ys;
  for (const auto& s : plot.series)
    for (const auto& segment : s.segments)
      for (const auto& p : segment) {
        if (!std::isfinite(p.x) || std::isnan(p.y)) continue;
        xs.push_back(p.x);
        if (std::isfinite(p.y)) ys.push_back(p.y);
      }
  if (xs.empty()) throw Error("plot '" + plot.title + "'", "nothing to plot");
  if (ys.empty()) ys = {0.0};  // every point infinite: they are drawn on the edges
  // Boundaries lie between points anyway; the first region may begin before the first point.
  for (size_t r = 1; r < plot.regions.size(); ++r)
    if (std::isfinite(plot.regions[r].start)) xs.push_back(plot.regions[r].start);
  // A frame axis runs edge to edge: little room at its ends.
  Axes axes = layout_axes(xs, ys, false, 860, 360, 0.02);
  if (plot.integer_x)
    axes.x_ticks.erase(std::remove_if(axes.x_ticks.begin(), axes.x_ticks.end(),
                                      [](double v) { return std::abs(v - std::round(v)) > 1e-9; }),
                       axes.x_ticks.end());
  const Box& area = axes.area;
  // y = +inf on the top edge, -inf on the bottom one.
  const auto at = [&](const Point2& p) {
    return Point2{axes.px(p.x), std::isinf(p.y) ? (p.y > 0 ? area.y0 : area.y1) : axes.py(p.y)};
  };

  Canvas probe(1, 1);
  double legend_width = 0;
  size_t legend_lines = plot.notes.size();
  for (const auto& s : plot.series) {
    legend_width = std::max(legend_width, probe.measure(s.name, kLegend).width());
    ++legend_lines;
  }
  if (!plot.boundary_name.empty()) {
    legend_width = std::max(legend_width, probe.measure(plot.boundary_name, kLegend).width());
    ++legend_lines;
  }
  for (const auto& t : plot.notes) legend_width = std::max(legend_width, probe.measure(t, kLegend).width());
  const auto [width, height] = axes.canvas_size(legend_width, legend_lines);
  auto canvas = std::make_unique<Canvas>(width, height);
  Canvas& c = *canvas;
  draw_axes(c, axes, plot.title, plot.x_label, plot.y_label);

  // Region boundaries under the lines, each region's name at the top: across the region where
  // it fits between its boundaries, else reading upwards along its boundary (narrow regions, a
  // few frames long), else not at all.
  const double name_baseline = area.y0 + 4 + probe.measure("Ag", kTick).height() - 3;
  for (size_t r = 0; r < plot.regions.size(); ++r) {
    const auto& region = plot.regions[r];
    if (!std::isfinite(region.start)) continue;
    const double x = axes.px(std::max(region.start, axes.x_lo));
    if (r > 0) c.line({x, area.y0}, {x, area.y1}, kLink, 1.2, true);
    if (plot.regions.size() < 2 || region.name.empty()) continue;
    Box room = area;
    room.x0 = x;
    if (r + 1 < plot.regions.size() && std::isfinite(plot.regions[r + 1].start))
      room.x1 = std::min(room.x1, axes.px(plot.regions[r + 1].start));
    const Box across = probe.measure(region.name, kTick, {x + 4, name_baseline}).grown(2);
    if (across.inside(room) && !collides(across, c.text_boxes())) {
      c.text({x + 4, name_baseline}, region.name, kTick);
      continue;
    }
    const Box flat = probe.measure(region.name, kTick);
    const Point2 centre{x + 3 + flat.height() / 2, area.y0 + 4 + flat.width() / 2};
    const Box along = Box{centre.x - flat.height() / 2, centre.y - flat.width() / 2, centre.x + flat.height() / 2,
                          centre.y + flat.width() / 2}.grown(1);
    if (along.inside(room) && !collides(along, c.text_boxes())) c.vertical_text(centre, region.name, kTick);
  }
  for (const auto& s : plot.series)
    for (const auto& segment : s.segments) {
      std::vector<Point2> line;
      std::vector<bool> on_edge;  // an infinite y
      for (const auto& p : segment)
        if (std::isfinite(p.x) && !std::isnan(p.y)) {
          line.push_back(at(p));
          on_edge.push_back(std::isinf(p.y));
        }
      if (line.size() == 1) c.marker(line.front(), Marker::Circle, 2.5, s.colour, true);
      c.polyline(line, s.colour, 1.5);
      for (size_t i = 0; i < line.size(); ++i)
        if (on_edge[i])
          c.marker(line[i], Marker::Circle, 3.5, s.colour, false);
        else if (s.dots)
          c.marker(line[i], Marker::Circle, 2, s.colour, true);
    }

  Legend legend(c, axes);
  for (const auto& s : plot.series) {
    c.line(legend.sample_start(), legend.sample_end(), s.colour, 1.5);
    if (s.dots) c.marker(legend.sample_centre(), Marker::Circle, 2, s.colour, true);
    legend.text(s.name);
  }
  if (!plot.boundary_name.empty()) {
    c.line(legend.sample_start(), legend.sample_end(), kLink, 1.2, true);
    legend.text(plot.boundary_name);
  }
  for (const auto& note : plot.notes) legend.text(note);
  return canvas;
}

void write_line_plot(const std::filesystem::path& path, const LinePlot& plot) { draw_line_plot(plot)->save(path); }

std::unique_ptr<Canvas> draw_bar_chart(const BarChart& chart) {
  std::vector<double> ys = {0.0};
  for (const auto& s : chart.series) {
    if (s.values.size() != chart.categories.size())
      throw Error("bar chart '" + chart.title + "'", "series '" + s.name + "' has " + std::to_string(s.values.size()) +
                                                         " values for " + std::to_string(chart.categories.size()) +
                                                         " categories");
    for (const auto* v : {&s.values, &s.low, &s.high})
      for (double y : *v)
        if (std::isfinite(y)) ys.push_back(y);
  }
  if (chart.categories.empty() || chart.series.empty()) throw Error("bar chart '" + chart.title + "'", "nothing to plot");
  const auto [y_lo, y_hi] = padded(*std::min_element(ys.begin(), ys.end()), *std::max_element(ys.begin(), ys.end()));
  const auto y_ticks = axis_ticks(y_lo, y_hi, false);

  Canvas probe(1, 1);
  double y_tick_width = 0, longest = 0, legend_width = 0;
  for (double v : y_ticks) y_tick_width = std::max(y_tick_width, probe.measure(tick_text(v), kTick).width());
  for (const auto& name : chart.categories) longest = std::max(longest, probe.measure(name, kTick).width());
  for (const auto& s : chart.series) legend_width = std::max(legend_width, probe.measure(s.name, kLegend).width());
  const double line_height = probe.measure("Ag", kLegend).height() + 5;
  const double group = std::max(60.0, 22.0 * chart.series.size() + 24);
  const double plot_w = group * chart.categories.size(), plot_h = 360;
  const double left = 14 + probe.measure("Ag", kAxis).height() + 10 + y_tick_width + 8;
  const double top = 16 + probe.measure("Ag", kTitle).height() + 14;
  const double bottom = longest + 16;  // category names read upwards under their group
  const Box area{left, top, left + plot_w, top + plot_h};
  const double title_width = probe.measure(chart.title, kTitle).width();
  const double width = std::max(left + plot_w + 24 + 22 + legend_width + 16, left + title_width + 16);
  const double height = std::max(top + plot_h + bottom, top + 10 + line_height * chart.series.size() + 10);
  auto canvas = std::make_unique<Canvas>(static_cast<int>(std::ceil(width)), static_cast<int>(std::ceil(height)));
  Canvas& c = *canvas;
  auto py = [&, y_lo = y_lo, y_hi = y_hi](double y) { return area.y1 - (y - y_lo) / (y_hi - y_lo) * plot_h; };

  c.text({left, 16 + probe.measure("Ag", kTitle).height() - 4}, chart.title, kTitle);
  c.vertical_text({14 + probe.measure("Ag", kAxis).height() / 2, area.y0 + plot_h / 2}, chart.y_label, kAxis);
  for (double v : y_ticks) {
    c.line({area.x0, py(v)}, {area.x1, py(v)}, kGrid);
    tick_label(c, {area.x0 - 6, py(v) + 4}, tick_text(v), Anchor::Right);
  }
  c.line({area.x0, py(0)}, {area.x1, py(0)}, kBlack);
  c.rectangle(area, kFrame, false);

  const double bar = (group - 24) / chart.series.size();
  for (size_t k = 0; k < chart.categories.size(); ++k) {
    const double x0 = area.x0 + k * group + 12;
    for (size_t i = 0; i < chart.series.size(); ++i) {
      const auto& s = chart.series[i];
      const double v = s.values[k];
      if (!std::isfinite(v)) continue;
      const double xa = x0 + i * bar, xb = xa + bar - 2;
      c.rectangle({xa, std::min(py(0), py(v)), xb, std::max(py(0), py(v))}, s.colour, true);
      if (k < s.low.size() && k < s.high.size() && std::isfinite(s.low[k]) && std::isfinite(s.high[k])) {
        const double xm = (xa + xb) / 2;
        c.line({xm, py(s.low[k])}, {xm, py(s.high[k])}, kBlack);
        c.line({xm - 3, py(s.low[k])}, {xm + 3, py(s.low[k])}, kBlack);
        c.line({xm - 3, py(s.high[k])}, {xm + 3, py(s.high[k])}, kBlack);
      }
    }
    const double name_width = probe.measure(chart.categories[k], kTick).width();
    c.vertical_text({area.x0 + k * group + group / 2, area.y1 + 8 + name_width / 2}, chart.categories[k], kTick);
  }
  double ly = area.y0 + 10 + line_height / 2;
  for (const auto& s : chart.series) {
    const double lx = area.x1 + 24;
    c.rectangle({lx, ly - 6, lx + 12, ly + 6}, s.colour, true);
    c.text({lx + 22, ly + 4}, s.name, kLegend);
    ly += line_height;
  }
  return canvas;
}

void write_bar_chart(const std::filesystem::path& path, const BarChart& chart) { draw_bar_chart(chart)->save(path); }

}  // namespace cgsr
