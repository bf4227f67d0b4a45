#include "core/plot.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/error.h"

namespace cgsr {
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

// "Nice" tick values covering [lo, hi] (for a log axis, lo and hi are log10 values).
std::vector<double> ticks(double lo, double hi, bool log_scale) {
  std::vector<double> out;
  if (log_scale) {
    for (int e = static_cast<int>(std::floor(lo)); e <= static_cast<int>(std::ceil(hi)); ++e)
      for (int m : {1, 2, 5}) {
        const double v = m * std::pow(10.0, e);
        if (std::log10(v) >= lo && std::log10(v) <= hi) out.push_back(v);
      }
    return out;
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
  for (double k = std::ceil(lo / step); k * step <= hi + 1e-12; k += 1) out.push_back(k * step);
  return out;
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
  const auto [x_lo, x_hi] = padded(*std::min_element(xs.begin(), xs.end()), *std::max_element(xs.begin(), xs.end()));
  const auto [y_lo, y_hi] = padded(*std::min_element(ys.begin(), ys.end()), *std::max_element(ys.begin(), ys.end()));
  const auto x_ticks = ticks(x_lo, x_hi, plot.log_x), y_ticks = ticks(y_lo, y_hi, false);

  // Margins from the text they hold; the legend column from its longest entry.
  Canvas probe(1, 1);
  double y_tick_width = 0;
  for (double v : y_ticks) y_tick_width = std::max(y_tick_width, probe.measure(tick_text(v), kTick).width());
  const double line_height = probe.measure("Ag", kLegend).height() + 5;
  std::vector<std::string> legend_texts;
  for (const auto& [y, text] : plot.horizontal_lines) legend_texts.push_back(text);
  for (const auto& s : plot.series)
    if (!s.name.empty()) legend_texts.push_back(s.name);
  if (!plot.links.empty() && !plot.links_name.empty()) legend_texts.push_back(plot.links_name);
  double legend_width = 0;
  for (const auto& t : legend_texts) legend_width = std::max(legend_width, probe.measure(t, kLegend).width());
  for (const auto& t : plot.notes) legend_width = std::max(legend_width, probe.measure(t, kLegend).width());

  const double plot_w = 640, plot_h = 460;
  const double left = 14 + probe.measure("Ag", kAxis).height() + 10 + y_tick_width + 8;
  const double top = 16 + probe.measure("Ag", kTitle).height() + 14;
  const double bottom = 8 + probe.measure("Ag", kTick).height() + 10 + probe.measure("Ag", kAxis).height() + 14;
  const Box area{left, top, left + plot_w, top + plot_h};
  auto px = [&, x_lo = x_lo, x_hi = x_hi](double x) {
    const double v = plot.log_x ? std::log10(std::max(x, 1e-12)) : x;
    return area.x0 + (v - x_lo) / (x_hi - x_lo) * plot_w;
  };
  auto py = [&, y_lo = y_lo, y_hi = y_hi](double y) { return area.y1 - (y - y_lo) / (y_hi - y_lo) * plot_h; };

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
  const double height = std::max(top + plot_h + bottom, top + 10 + line_height * legend_lines + 10);
  const double width = left + plot_w + 24 + 30 + legend_width + 16;
  auto canvas = std::make_unique<Canvas>(static_cast<int>(std::ceil(width)), static_cast<int>(std::ceil(height)));
  Canvas& c = *canvas;

  c.text({area.x0 + plot_w / 2, 16 + probe.measure("Ag", kTitle).height() - 4}, plot.title, kTitle, Anchor::Centre);
  c.vertical_text({14 + probe.measure("Ag", kAxis).height() / 2, area.y0 + plot_h / 2}, plot.y_label, kAxis);
  c.text({area.x0 + plot_w / 2, height - 12}, plot.x_label, kAxis, Anchor::Centre);
  for (double v : x_ticks) {
    c.line({px(v), area.y0}, {px(v), area.y1}, kGrid);
    tick_label(c, {px(v), area.y1 + 8 + probe.measure("Ag", kTick).height() - 3}, tick_text(v), Anchor::Centre);
  }
  for (double v : y_ticks) {
    c.line({area.x0, py(v)}, {area.x1, py(v)}, kGrid);
    tick_label(c, {area.x0 - 6, py(v) + 4}, tick_text(v), Anchor::Right);
  }
  c.rectangle(area, kFrame, false);

  // The legend, right of the plot: a sample of each series' line or marker, then the notes.
  const double lx = area.x1 + 24;
  double ly = area.y0 + 10 + line_height / 2;
  auto legend_text = [&](const std::string& text) {
    c.text({lx + 30, ly + 4}, text, kLegend);
    ly += line_height;
  };
  for (const auto& [y, text] : plot.horizontal_lines) {
    c.line({area.x0, py(y)}, {area.x1, py(y)}, {120, 120, 120}, 1, true);
    c.line({lx, ly}, {lx + 22, ly}, {120, 120, 120}, 1, true);
    legend_text(text);
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
    if (s.connect) c.line({lx, ly}, {lx + 22, ly}, s.colour, 1.5);
    c.marker({lx + 11, ly}, s.marker, std::min(s.radius, 6.0), s.colour, s.filled);
    legend_text(s.name);
  }
  if (!plot.links.empty() && !plot.links_name.empty()) {
    c.line({lx, ly}, {lx + 22, ly}, kLink, 1.6, true);
    legend_text(plot.links_name);
  }
  for (const auto& note : plot.notes) legend_text(note);
  for (const auto& n : numbered) legend_text(n);

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
  const auto y_ticks = ticks(y_lo, y_hi, false);

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
