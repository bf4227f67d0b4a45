#include "core/plot.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"

namespace cgsr {
namespace {
cv::Scalar bgr(const Rgb& c) { return cv::Scalar(c[2], c[1], c[0]); }

std::string tick_text(double v) {
  std::ostringstream s;
  s.precision(v != 0 && std::abs(v) < 1 ? 2 : 4);
  s << v;
  return s.str();
}

void write_png(const std::filesystem::path& path, const cv::Mat& img) {
  std::vector<unsigned char> png;
  if (!cv::imencode(".png", img, png)) throw Error(path.string(), "cannot encode the plot");
  write_file_atomic(path, std::string(png.begin(), png.end()));
}

// "Nice" tick values covering [lo, hi].
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
}  // namespace

void write_scatter_plot(const std::filesystem::path& path, const ScatterPlot& plot) {
  std::vector<double> xs, ys;
  for (const auto& s : plot.series)
    for (const auto& p : s.points) {
      if (plot.log_x && p.x <= 0) continue;
      xs.push_back(plot.log_x ? std::log10(p.x) : p.x);
      ys.push_back(p.y);
    }
  for (const auto& [y, text] : plot.horizontal_lines) ys.push_back(y);
  if (ys.empty()) throw Error(path.string(), "nothing to plot");
  if (xs.empty()) xs = {0.0, 1.0};

  // The legend column grows with its longest entry, so no entry is cut off at the image's edge.
  int longest = 0;
  auto measure = [&](const std::string& text) {
    longest = std::max(longest, cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, 0.42, 1, nullptr).width);
  };
  for (const auto& [y, text] : plot.horizontal_lines) measure("--- " + text);
  for (const auto& s : plot.series) measure(s.name);
  for (const auto& note : plot.notes) measure(note);
  const int left = 80, right = std::max(300, longest + 24), top = 50, bottom = 70;
  const int width = 660 + right, height = 600;
  auto pad = [](double lo, double hi) {
    const double margin = hi > lo ? 0.08 * (hi - lo) : 0.5;
    return std::make_pair(lo - margin, hi + margin);
  };
  const auto [x_lo, x_hi] = pad(*std::min_element(xs.begin(), xs.end()), *std::max_element(xs.begin(), xs.end()));
  const auto [y_lo, y_hi] = pad(*std::min_element(ys.begin(), ys.end()), *std::max_element(ys.begin(), ys.end()));
  auto px = [&, x_lo = x_lo, x_hi = x_hi](double x) {
    const double v = plot.log_x ? std::log10(std::max(x, 1e-12)) : x;
    return static_cast<int>(left + (v - x_lo) / (x_hi - x_lo) * (width - left - right));
  };
  auto py = [&, y_lo = y_lo, y_hi = y_hi](double y) {
    return static_cast<int>(height - bottom - (y - y_lo) / (y_hi - y_lo) * (height - top - bottom));
  };

  cv::Mat img(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  const cv::Scalar black(0, 0, 0), grey(215, 215, 215);
  for (double v : ticks(x_lo, x_hi, plot.log_x)) {
    const int x = px(v);
    cv::line(img, {x, top}, {x, height - bottom}, grey, 1);
    cv::putText(img, tick_text(v), {x - 14, height - bottom + 20}, cv::FONT_HERSHEY_SIMPLEX, 0.45, black);
  }
  for (double v : ticks(y_lo, y_hi, false)) {
    const int y = py(v);
    cv::line(img, {left, y}, {width - right, y}, grey, 1);
    cv::putText(img, tick_text(v), {8, y + 5}, cv::FONT_HERSHEY_SIMPLEX, 0.45, black);
  }
  cv::rectangle(img, {left, top}, {width - right, height - bottom}, black, 1);
  cv::putText(img, plot.x_label, {left + 150, height - 25}, cv::FONT_HERSHEY_SIMPLEX, 0.55, black);
  cv::putText(img, plot.y_label, {8, top - 15}, cv::FONT_HERSHEY_SIMPLEX, 0.55, black);
  cv::putText(img, plot.title, {left + 120, 28}, cv::FONT_HERSHEY_SIMPLEX, 0.7, black, 2);

  int legend_y = top + 10;
  auto legend = [&](const std::string& text, const cv::Scalar& colour) {
    cv::putText(img, text, {width - right + 12, legend_y}, cv::FONT_HERSHEY_SIMPLEX, 0.42, colour);
    legend_y += 18;
  };
  for (const auto& [y, text] : plot.horizontal_lines) {
    cv::line(img, {left, py(y)}, {width - right, py(y)}, cv::Scalar(120, 120, 120), 1, cv::LINE_AA);
    legend("--- " + text, cv::Scalar(90, 90, 90));
  }
  for (const auto& s : plot.series) {
    const cv::Scalar colour = bgr(s.colour);
    if (s.connect && s.points.size() > 1) {
      auto sorted = s.points;
      std::sort(sorted.begin(), sorted.end(), [](const PlotPoint& a, const PlotPoint& b) { return a.x < b.x; });
      for (size_t i = 1; i < sorted.size(); ++i)
        cv::line(img, {px(sorted[i - 1].x), py(sorted[i - 1].y)}, {px(sorted[i].x), py(sorted[i].y)}, colour, 2,
                 cv::LINE_AA);
    }
    for (const auto& p : s.points) {
      if (plot.log_x && p.x <= 0) continue;
      const cv::Point at(px(p.x), py(p.y));
      cv::circle(img, at, s.radius, colour, cv::FILLED, cv::LINE_AA);
      if (!p.label.empty())
        cv::putText(img, p.label, at + cv::Point(7, -6), cv::FONT_HERSHEY_SIMPLEX, 0.42, black);
    }
    if (!s.name.empty()) legend(s.name, colour);
  }
  for (const auto& note : plot.notes) legend(note, black);

  write_png(path, img);
}

void write_bar_chart(const std::filesystem::path& path, const BarChart& chart) {
  std::vector<double> ys = {0.0};
  for (const auto& s : chart.series) {
    if (s.values.size() != chart.categories.size())
      throw Error(path.string(), "bar series '" + s.name + "' has " + std::to_string(s.values.size()) +
                                     " values for " + std::to_string(chart.categories.size()) + " categories");
    for (const auto* v : {&s.values, &s.low, &s.high})
      for (double y : *v)
        if (std::isfinite(y)) ys.push_back(y);
  }
  if (chart.categories.empty() || chart.series.empty()) throw Error(path.string(), "nothing to plot");
  const double lo = *std::min_element(ys.begin(), ys.end()), hi = *std::max_element(ys.begin(), ys.end());
  const double margin = hi > lo ? 0.08 * (hi - lo) : 0.5, y_lo = lo - margin, y_hi = hi + margin;

  const int group = std::max(60, 22 * static_cast<int>(chart.series.size()) + 24);
  // Room below the axis for the longest category name, written downwards.
  int longest = 0;
  for (const auto& name : chart.categories)
    longest = std::max(longest, cv::getTextSize(name, cv::FONT_HERSHEY_SIMPLEX, 0.42, 1, nullptr).width);
  const int left = 80, right = 220, top = 50, bottom = std::max(150, longest + 24);
  const int width = left + right + group * static_cast<int>(chart.categories.size()), height = 410 + bottom;
  auto py = [&](double y) { return static_cast<int>(height - bottom - (y - y_lo) / (y_hi - y_lo) * (height - top - bottom)); };

  cv::Mat img(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  const cv::Scalar black(0, 0, 0), grey(215, 215, 215);
  for (double v : ticks(y_lo, y_hi, false)) {
    cv::line(img, {left, py(v)}, {width - right, py(v)}, grey, 1);
    cv::putText(img, tick_text(v), {8, py(v) + 5}, cv::FONT_HERSHEY_SIMPLEX, 0.45, black);
  }
  cv::line(img, {left, py(0)}, {width - right, py(0)}, black, 1);
  cv::rectangle(img, {left, top}, {width - right, height - bottom}, black, 1);
  cv::putText(img, chart.y_label, {8, top - 15}, cv::FONT_HERSHEY_SIMPLEX, 0.55, black);
  cv::putText(img, chart.title, {left + 20, 28}, cv::FONT_HERSHEY_SIMPLEX, 0.7, black, 2);

  const int bar = (group - 24) / static_cast<int>(chart.series.size());
  for (size_t c = 0; c < chart.categories.size(); ++c) {
    const int x0 = left + static_cast<int>(c) * group + 12;
    for (size_t k = 0; k < chart.series.size(); ++k) {
      const auto& s = chart.series[k];
      const double v = s.values[c];
      if (!std::isfinite(v)) continue;
      const int xa = x0 + static_cast<int>(k) * bar, xb = xa + bar - 2;
      cv::rectangle(img, {xa, std::min(py(0), py(v))}, {xb, std::max(py(0), py(v))}, bgr(s.colour), cv::FILLED);
      if (c < s.low.size() && c < s.high.size() && std::isfinite(s.low[c]) && std::isfinite(s.high[c])) {
        const int xm = (xa + xb) / 2;
        cv::line(img, {xm, py(s.low[c])}, {xm, py(s.high[c])}, black, 1);
        cv::line(img, {xm - 3, py(s.low[c])}, {xm + 3, py(s.low[c])}, black, 1);
        cv::line(img, {xm - 3, py(s.high[c])}, {xm + 3, py(s.high[c])}, black, 1);
      }
    }
    // Category names run downwards at 90 degrees: drawn on a strip, then rotated.
    const std::string& name = chart.categories[c];
    cv::Mat strip(group - 8, bottom - 10, CV_8UC3, cv::Scalar(255, 255, 255));
    cv::putText(strip, name, {4, (group - 8) / 2 + 5}, cv::FONT_HERSHEY_SIMPLEX, 0.42, black);
    cv::Mat turned;
    cv::rotate(strip, turned, cv::ROTATE_90_CLOCKWISE);
    turned.copyTo(img(cv::Rect(x0 - 8, height - bottom + 6, turned.cols, turned.rows)));
  }
  int legend_y = top + 10;
  for (const auto& s : chart.series) {
    cv::rectangle(img, {width - right + 12, legend_y - 10}, {width - right + 24, legend_y}, bgr(s.colour), cv::FILLED);
    cv::putText(img, s.name, {width - right + 30, legend_y}, cv::FONT_HERSHEY_SIMPLEX, 0.42, black);
    legend_y += 18;
  }
  write_png(path, img);
}

}  // namespace cgsr
