#pragma once
// Sub-pixel BSP border images (after the sub-pixel BSP images paper): for every pixel that a
// geometry border crosses, a shallow BSP tree of the border's lines, each leaf with the colour
// of the surface on its side. Read at any resolution, the edges stay where the geometry put them.
// (Not the Quake III map format of render_data/q3/.)
//
// Coordinates are the image's pixel coordinates: x right, y down, pixel (row i, column j) spans
// [j, j+1] x [i, i+1]. A split's line is a*x + b*y + c = 0 with a^2 + b^2 = 1; the first child is
// the side a*x + b*y + c >= 0, the second the side < 0.
//
// A tree is stored in preorder: node k is a split when bit k of `shape` is set, else a leaf; the
// splits' lines and the leaves' colours each in preorder. A tree of depth d (lines on the longest
// path from the root) has at most 2^d - 1 splits; depth is at most kMaxBspDepth.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace cgsr {

constexpr int kMaxBspDepth = 4;  // 15 splits and 16 leaves: 31 nodes fit the 32 bits of `shape`

struct BspLine {
  float a = 0, b = 0, c = 0;
  double side(double x, double y) const { return static_cast<double>(a) * x + static_cast<double>(b) * y + c; }
};

using Rgb8 = std::array<uint8_t, 3>;  // sRGB-encoded, as the colour image stores it

struct BspTree {
  uint32_t shape = 0;
  std::vector<BspLine> lines;  // one per split, preorder
  std::vector<Rgb8> leaves;    // one per leaf, preorder (lines.size() + 1 of them)

  // The leaf that (x, y) falls in (any point: lines extend beyond the pixel).
  int leaf_at(double x, double y) const;
  // Lines on the longest root-to-leaf path.
  int depth() const;
  // Empty when the shape, lines and leaves agree (a full binary tree in preorder, one line per
  // split, one colour per leaf, every line finite and of unit normal), else what is wrong.
  std::string problem() const;
};

// The trees of one frame at one resolution, by pixel.
class BspBorderImage {
 public:
  BspBorderImage() = default;
  BspBorderImage(int width, int height, int max_depth);

  int width() const { return width_; }
  int height() const { return height_; }
  int max_depth() const { return max_depth_; }

  // Pixels must be added in ascending order (row-major index), each at most once.
  void add(int pixel, BspTree tree);
  // The tree of pixel (x, y) (column, row), or null when no border crosses it.
  const BspTree* at(int x, int y) const;

  size_t size() const { return pixels_.size(); }  // border pixels
  int pixel(size_t k) const { return pixels_[k]; }
  const BspTree& tree(size_t k) const { return trees_[k]; }
  size_t line_count() const;  // over every tree
  double border_fraction() const;  // border pixels / all pixels
  size_t bytes() const;  // memory held (for the frame cache)

 private:
  int width_ = 0, height_ = 0, max_depth_ = 0;
  std::vector<int> pixels_;         // ascending
  std::vector<BspTree> trees_;      // parallel to pixels_
  std::vector<int32_t> index_;      // per pixel: its position in pixels_, -1 for none
};

}  // namespace cgsr
