#include "render_data/bsp_border.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace cgsr {
namespace {
bool is_split(uint32_t shape, int node) { return node < 32 && ((shape >> node) & 1u) != 0; }

// Nodes in the subtree rooted at `node` (preorder: it ends where the open splits are all closed).
int subtree_size(uint32_t shape, int node) {
  int open = 1, k = node;
  while (open > 0 && k < 32) {
    open += is_split(shape, k) ? 1 : -1;
    ++k;
  }
  return k - node;
}

int popcount_below(uint32_t shape, int node) {
  int n = 0;
  for (int k = 0; k < node; ++k) n += is_split(shape, k);
  return n;
}

int depth_from(uint32_t shape, int node) {
  if (!is_split(shape, node)) return 0;
  const int first = node + 1, second = first + subtree_size(shape, first);
  return 1 + std::max(depth_from(shape, first), depth_from(shape, second));
}
}  // namespace

int BspTree::leaf_at(double x, double y) const {
  int node = 0;
  while (is_split(shape, node)) {
    const BspLine& l = lines[popcount_below(shape, node)];
    node = l.side(x, y) >= 0 ? node + 1 : node + 1 + subtree_size(shape, node + 1);
  }
  return node - popcount_below(shape, node);
}

int BspTree::depth() const { return depth_from(shape, 0); }

std::string BspTree::problem() const {
  // A full binary tree in preorder closes after exactly 2 * splits + 1 nodes.
  int open = 1, nodes = 0;
  while (open > 0 && nodes < 32) open += is_split(shape, nodes++) ? 1 : -1;
  if (open > 0) return "shape " + std::to_string(shape) + " does not close within 32 nodes";
  if (nodes < 32 && (shape >> nodes) != 0)
    return "shape " + std::to_string(shape) + " has split bits after its last node (" + std::to_string(nodes) + ")";
  const int splits = popcount_below(shape, nodes);
  if (static_cast<int>(lines.size()) != splits)
    return std::to_string(lines.size()) + " line(s) for a shape of " + std::to_string(splits) + " split(s)";
  if (static_cast<int>(leaves.size()) != splits + 1)
    return std::to_string(leaves.size()) + " leaf colour(s) for a shape of " + std::to_string(splits + 1) + " leaves";
  for (size_t i = 0; i < lines.size(); ++i) {
    const BspLine& l = lines[i];
    if (!std::isfinite(l.a) || !std::isfinite(l.b) || !std::isfinite(l.c))
      return "line " + std::to_string(i) + " has a non-finite coefficient";
    const double n = static_cast<double>(l.a) * l.a + static_cast<double>(l.b) * l.b;
    if (std::abs(n - 1.0) > 1e-3) return "line " + std::to_string(i) + " has a^2 + b^2 = " + std::to_string(n) + ", not 1";
  }
  return "";
}

BspBorderImage::BspBorderImage(int width, int height, int max_depth)
    : width_(width), height_(height), max_depth_(max_depth), index_(static_cast<size_t>(width) * height, -1) {
  CGSR_CHECK(width > 0 && height > 0, "a BSP border image needs pixels");
  CGSR_CHECK(max_depth >= 1 && max_depth <= kMaxBspDepth, "BSP depth out of range");
}

void BspBorderImage::add(int pixel, BspTree tree) {
  CGSR_CHECK(pixel >= 0 && static_cast<size_t>(pixel) < index_.size(), "BSP pixel outside the image");
  CGSR_CHECK(pixels_.empty() || pixel > pixels_.back(), "BSP pixels must be added in ascending order");
  CGSR_CHECK(tree.problem().empty() && tree.depth() <= max_depth_ && !tree.lines.empty(), "malformed BSP tree");
  index_[pixel] = static_cast<int32_t>(pixels_.size());
  pixels_.push_back(pixel);
  trees_.push_back(std::move(tree));
}

const BspTree* BspBorderImage::at(int x, int y) const {
  if (x < 0 || y < 0 || x >= width_ || y >= height_) return nullptr;
  const int32_t k = index_[static_cast<size_t>(y) * width_ + x];
  return k >= 0 ? &trees_[k] : nullptr;
}

size_t BspBorderImage::line_count() const {
  size_t n = 0;
  for (const auto& t : trees_) n += t.lines.size();
  return n;
}

double BspBorderImage::border_fraction() const {
  return index_.empty() ? 0.0 : static_cast<double>(pixels_.size()) / static_cast<double>(index_.size());
}

size_t BspBorderImage::bytes() const {
  size_t n = index_.size() * sizeof(int32_t) + pixels_.size() * (sizeof(int) + sizeof(BspTree));
  for (const auto& t : trees_) n += t.lines.size() * sizeof(BspLine) + t.leaves.size() * sizeof(Rgb8);
  return n;
}

}  // namespace cgsr
