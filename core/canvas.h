#pragma once
// A drawing surface for plots and image grids, drawn with Cairo and saved as PNG, SVG or PDF
// (by the file's extension). Text is laid out with the metrics of the font it is drawn in, and
// every text's box is recorded, so that a layout can avoid its own labels and a test can check
// that no text overlaps another or leaves the canvas.
//
//   Canvas c(400, 300);
//   c.text({200, 20}, "title", {16, true}, Anchor::Centre);
//   c.line({10, 10}, {390, 290}, {40, 90, 180});
//   c.save("plot.svg");

#include <array>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace cv {
class Mat;
}

namespace cgsr {

using Rgb = std::array<int, 3>;

struct Point2 {
  double x = 0, y = 0;
};

// An axis-aligned box in canvas pixels, y pointing down.
struct Box {
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  double width() const { return x1 - x0; }
  double height() const { return y1 - y0; }
  bool overlaps(const Box& other) const;  // they share an area (touching edges do not)
  bool inside(const Box& outer) const;
  Box grown(double margin) const;
};

struct TextStyle {
  double size = 12;  // pixels
  bool bold = false;
  Rgb colour{0, 0, 0};
};

enum class Anchor { Left, Centre, Right };  // where the given point is along the text

enum class Marker { Circle, Square, Diamond, Triangle };

class Canvas {
 public:
  Canvas(int width, int height);
  ~Canvas();
  Canvas(const Canvas&) = delete;
  Canvas& operator=(const Canvas&) = delete;

  int width() const { return width_; }
  int height() const { return height_; }
  Box bounds() const { return {0, 0, double(width_), double(height_)}; }

  // The box `text` would take with its baseline's anchor point at `at` (nothing is drawn).
  Box measure(const std::string& text, const TextStyle& style, Point2 at = {}, Anchor anchor = Anchor::Left) const;
  // Draws the text and records its box; `vertical` turns it to read upwards, centred on `at`.
  Box text(Point2 at, const std::string& text, const TextStyle& style, Anchor anchor = Anchor::Left);
  Box vertical_text(Point2 centre, const std::string& text, const TextStyle& style);
  const std::vector<Box>& text_boxes() const { return text_boxes_; }

  void line(Point2 a, Point2 b, const Rgb& colour, double width = 1, bool dashed = false);
  void polyline(const std::vector<Point2>& points, const Rgb& colour, double width = 1);
  void rectangle(const Box& box, const Rgb& colour, bool filled, double width = 1);
  void marker(Point2 at, Marker shape, double radius, const Rgb& colour, bool filled);
  // An 8-bit BGR (OpenCV) image with its top-left corner at `at`, drawn pixel for pixel.
  void image(Point2 at, const cv::Mat& bgr);

  // Writes the canvas atomically as PNG, SVG or PDF by the path's extension; any other extension
  // is an error naming the path.
  void save(const std::filesystem::path& path) const;

 private:
  struct Surface;
  int width_, height_;
  std::unique_ptr<Surface> surface_;
  std::vector<Box> text_boxes_;
};

}  // namespace cgsr
