#include "core/canvas.h"

#include <cairo-pdf.h>
#include <cairo-svg.h>
#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/atomic_file.h"
#include "core/error.h"

namespace cgsr {

bool Box::overlaps(const Box& o) const { return x0 < o.x1 && o.x0 < x1 && y0 < o.y1 && o.y0 < y1; }
bool Box::inside(const Box& o) const { return x0 >= o.x0 && y0 >= o.y0 && x1 <= o.x1 && y1 <= o.y1; }
Box Box::grown(double m) const { return {x0 - m, y0 - m, x1 + m, y1 + m}; }

namespace {
// DejaVu Sans (Debian's fonts-dejavu-core) through fontconfig: the same metrics for every format.
constexpr const char* kFont = "DejaVu Sans";

void set_colour(cairo_t* cr, const Rgb& c) { cairo_set_source_rgb(cr, c[0] / 255.0, c[1] / 255.0, c[2] / 255.0); }

void set_font(cairo_t* cr, const TextStyle& style) {
  cairo_select_font_face(cr, kFont, CAIRO_FONT_SLANT_NORMAL, style.bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, style.size);
}

cairo_status_t append_to_string(void* closure, const unsigned char* data, unsigned int length) {
  static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
  return CAIRO_STATUS_SUCCESS;
}
}  // namespace

// Drawing goes to a recording surface; save() replays it onto the format's surface.
struct Canvas::Surface {
  cairo_surface_t* recording = nullptr;
  cairo_t* cr = nullptr;
  ~Surface() {
    if (cr) cairo_destroy(cr);
    if (recording) cairo_surface_destroy(recording);
  }
};

Canvas::Canvas(int width, int height) : width_(width), height_(height), surface_(std::make_unique<Surface>()) {
  if (width <= 0 || height <= 0 || width > 20000 || height > 20000)
    throw Error("canvas", "size " + std::to_string(width) + "x" + std::to_string(height) + " out of range [1, 20000]",
                ErrorKind::Internal);
  const cairo_rectangle_t extents{0, 0, double(width), double(height)};
  surface_->recording = cairo_recording_surface_create(CAIRO_CONTENT_COLOR_ALPHA, &extents);
  surface_->cr = cairo_create(surface_->recording);
  cairo_set_source_rgb(surface_->cr, 1, 1, 1);
  cairo_paint(surface_->cr);
}

Canvas::~Canvas() = default;

Box Canvas::measure(const std::string& text, const TextStyle& style, Point2 at, Anchor anchor) const {
  cairo_t* cr = surface_->cr;
  cairo_save(cr);
  set_font(cr, style);
  cairo_text_extents_t t;
  cairo_font_extents_t f;
  cairo_text_extents(cr, text.c_str(), &t);
  cairo_font_extents(cr, &f);
  cairo_restore(cr);
  // The advance and the font's ascent and descent: labels of one style line up and have one height.
  const double w = t.x_advance;
  const double x = anchor == Anchor::Left ? at.x : anchor == Anchor::Centre ? at.x - w / 2 : at.x - w;
  return {x, at.y - f.ascent, x + w, at.y + f.descent};
}

Box Canvas::text(Point2 at, const std::string& text, const TextStyle& style, Anchor anchor) {
  const Box box = measure(text, style, at, anchor);
  cairo_t* cr = surface_->cr;
  cairo_save(cr);
  set_font(cr, style);
  set_colour(cr, style.colour);
  cairo_move_to(cr, box.x0, at.y);
  cairo_show_text(cr, text.c_str());
  cairo_restore(cr);
  text_boxes_.push_back(box);
  return box;
}

Box Canvas::vertical_text(Point2 centre, const std::string& text, const TextStyle& style) {
  const Box flat = measure(text, style);  // baseline at y = 0
  cairo_t* cr = surface_->cr;
  cairo_save(cr);
  set_font(cr, style);
  set_colour(cr, style.colour);
  // Reading upwards: the text's x runs up the canvas and its glyphs' tops point left, so the
  // baseline sits right of the centre by half of (ascent - descent).
  const double baseline_x = centre.x - (flat.y0 + flat.y1) / 2;
  cairo_move_to(cr, baseline_x, centre.y + flat.width() / 2);
  cairo_rotate(cr, -M_PI / 2);
  cairo_show_text(cr, text.c_str());
  cairo_restore(cr);
  const Box box{centre.x - flat.height() / 2, centre.y - flat.width() / 2, centre.x + flat.height() / 2,
                centre.y + flat.width() / 2};
  text_boxes_.push_back(box);
  return box;
}

void Canvas::line(Point2 a, Point2 b, const Rgb& colour, double width, bool dashed) {
  cairo_t* cr = surface_->cr;
  cairo_save(cr);
  set_colour(cr, colour);
  cairo_set_line_width(cr, width);
  if (dashed) {
    const double dash[] = {5.0, 4.0};
    cairo_set_dash(cr, dash, 2, 0);
  }
  cairo_move_to(cr, a.x, a.y);
  cairo_line_to(cr, b.x, b.y);
  cairo_stroke(cr);
  cairo_restore(cr);
}

void Canvas::polyline(const std::vector<Point2>& points, const Rgb& colour, double width) {
  if (points.size() < 2) return;
  cairo_t* cr = surface_->cr;
  cairo_save(cr);
  set_colour(cr, colour);
  cairo_set_line_width(cr, width);
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  cairo_move_to(cr, points[0].x, points[0].y);
  for (size_t i = 1; i < points.size(); ++i) cairo_line_to(cr, points[i].x, points[i].y);
  cairo_stroke(cr);
  cairo_restore(cr);
}

void Canvas::rectangle(const Box& box, const Rgb& colour, bool filled, double width) {
  cairo_t* cr = surface_->cr;
  cairo_save(cr);
  set_colour(cr, colour);
  cairo_rectangle(cr, box.x0, box.y0, box.width(), box.height());
  if (filled) {
    cairo_fill(cr);
  } else {
    cairo_set_line_width(cr, width);
    cairo_stroke(cr);
  }
  cairo_restore(cr);
}

void Canvas::marker(Point2 at, Marker shape, double r, const Rgb& colour, bool filled) {
  cairo_t* cr = surface_->cr;
  cairo_save(cr);
  set_colour(cr, colour);
  switch (shape) {
    case Marker::Circle:
      cairo_arc(cr, at.x, at.y, r, 0, 2 * M_PI);
      break;
    case Marker::Square:
      cairo_rectangle(cr, at.x - r * 0.85, at.y - r * 0.85, 1.7 * r, 1.7 * r);
      break;
    case Marker::Diamond:
      cairo_move_to(cr, at.x, at.y - 1.25 * r);
      cairo_line_to(cr, at.x + 1.25 * r, at.y);
      cairo_line_to(cr, at.x, at.y + 1.25 * r);
      cairo_line_to(cr, at.x - 1.25 * r, at.y);
      cairo_close_path(cr);
      break;
    case Marker::Triangle:
      cairo_move_to(cr, at.x, at.y - 1.2 * r);
      cairo_line_to(cr, at.x + 1.1 * r, at.y + 0.8 * r);
      cairo_line_to(cr, at.x - 1.1 * r, at.y + 0.8 * r);
      cairo_close_path(cr);
      break;
  }
  if (filled) {
    cairo_fill(cr);
  } else {
    // A hollow marker: white inside, so the lines under it do not run through it.
    cairo_fill_preserve(cr);
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_fill_preserve(cr);
    set_colour(cr, colour);
    cairo_set_line_width(cr, 2);
    cairo_stroke(cr);
  }
  cairo_restore(cr);
}

void Canvas::image(Point2 at, const cv::Mat& bgr) {
  if (bgr.empty() || bgr.type() != CV_8UC3) throw Error("canvas", "image() takes an 8-bit BGR image", ErrorKind::Internal);
  // Cairo's RGB24 is a native-endian 32-bit word per pixel: B, G, R, unused in memory on x86.
  cairo_surface_t* img = cairo_image_surface_create(CAIRO_FORMAT_RGB24, bgr.cols, bgr.rows);
  cairo_surface_flush(img);
  unsigned char* data = cairo_image_surface_get_data(img);
  const int stride = cairo_image_surface_get_stride(img);
  for (int y = 0; y < bgr.rows; ++y) {
    cv::Mat row(1, bgr.cols, CV_8UC4, data + static_cast<size_t>(y) * stride);
    cv::cvtColor(bgr.row(y), row, cv::COLOR_BGR2BGRA);
  }
  cairo_surface_mark_dirty(img);
  cairo_t* cr = surface_->cr;
  cairo_save(cr);
  cairo_set_source_surface(cr, img, at.x, at.y);
  cairo_pattern_set_filter(cairo_get_source(cr), CAIRO_FILTER_NEAREST);
  cairo_paint(cr);
  cairo_restore(cr);
  cairo_surface_destroy(img);  // the recording keeps its own reference
}

void Canvas::save(const std::filesystem::path& path) const {
  const std::string ext = path.extension().string();
  std::string bytes;
  cairo_surface_t* target = nullptr;
  if (ext == ".png")
    target = cairo_image_surface_create(CAIRO_FORMAT_RGB24, width_, height_);
  else if (ext == ".svg")
    target = cairo_svg_surface_create_for_stream(append_to_string, &bytes, width_, height_);
  else if (ext == ".pdf")
    target = cairo_pdf_surface_create_for_stream(append_to_string, &bytes, width_, height_);
  else
    throw Error(path.string(), "a canvas is saved as .png, .svg or .pdf, not '" + ext + "'", ErrorKind::Internal);
  cairo_t* cr = cairo_create(target);
  cairo_set_source_surface(cr, surface_->recording, 0, 0);
  cairo_paint(cr);
  cairo_destroy(cr);
  if (ext == ".png") cairo_surface_write_to_png_stream(target, append_to_string, &bytes);
  cairo_surface_finish(target);  // flushes SVG and PDF into `bytes`
  const cairo_status_t status = cairo_surface_status(target);
  cairo_surface_destroy(target);
  if (status != CAIRO_STATUS_SUCCESS || bytes.empty())
    throw Error(path.string(), std::string("cannot draw the canvas: ") + cairo_status_to_string(status),
                ErrorKind::Internal);
  write_file_atomic(path, bytes);
}

}  // namespace cgsr
