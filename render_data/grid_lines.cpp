#include "render_data/grid_lines.h"

#include <torch/torch.h>

#include <vector>

namespace cgsr {
namespace {

// Best (period, offset) over a density profile; {0, 0} when no grid stands out.
std::pair<int, int> find_period(const std::vector<double>& density, const GridLineSettings& s) {
  const int n = static_cast<int>(density.size());
  double total = 0;
  for (double d : density) total += d;
  std::pair<int, int> best{0, 0};
  double best_score = 0;
  for (int p = 4; p <= n / 3; ++p)
    for (int o = 0; o < p; ++o) {
      double on = 0, off_sum = 0;
      int count = 0;
      for (int i = o; i < n; i += p) on += density[i], ++count;
      if (count < 3) continue;
      const double mean_on = on / count;
      off_sum = total - on;
      const double mean_off = off_sum / std::max(1, n - count);
      if (mean_on < s.min_line_density || mean_on < s.contrast * mean_off + 0.1) continue;
      // Every grid line must be dense, not just the average (a few real edges on one line).
      int dense = 0;
      for (int i = o; i < n; i += p) dense += density[i] >= 0.5 * mean_on;
      if (dense < count) continue;
      const double score = mean_on - mean_off;
      // Multiples of the true period score the same: keep the smallest period that is as good.
      if (score > best_score * 1.05) {
        best_score = score;
        best = {p, o};
      }
    }
  return best;
}

}  // namespace

GridLines detect_grid_lines(const torch::Tensor& edge, const GridLineSettings& settings) {
  const auto e = (edge.dim() == 3 ? edge[0] : edge).to(torch::kFloat64).gt(0.5).to(torch::kFloat64);
  const auto rows = e.mean(1).contiguous(), cols = e.mean(0).contiguous();
  const std::vector<double> r(rows.data_ptr<double>(), rows.data_ptr<double>() + rows.numel());
  const std::vector<double> c(cols.data_ptr<double>(), cols.data_ptr<double>() + cols.numel());
  GridLines g;
  std::tie(g.row_period, g.row_offset) = find_period(r, settings);
  std::tie(g.col_period, g.col_offset) = find_period(c, settings);
  return g;
}

torch::Tensor remove_grid_lines(const torch::Tensor& edge, const GridLines& lines) {
  if (!lines.found()) return edge.clone();
  auto e = (edge.dim() == 3 ? edge[0] : edge).clone();
  const int64_t H = e.size(0), W = e.size(1);
  // Edge pixels off the grid lines: the only evidence that a line pixel is a real edge.
  auto grid = torch::zeros({H, W}, torch::kBool);
  if (lines.row_period > 0) grid.slice(0, lines.row_offset, H, lines.row_period).fill_(true);
  if (lines.col_period > 0) grid.slice(1, lines.col_offset, W, lines.col_period).fill_(true);
  const auto on = e.gt(0) & ~grid;
  auto zero = torch::zeros({}, e.options());
  // A pixel on a grid line stays when a real edge crosses the line there.
  auto clear = [&](int dim, int period, int offset) {
    const int64_t n = dim == 0 ? H : W;
    for (int64_t i = offset; i < n; i += period) {
      auto line = e.select(dim, i);
      // A real edge continues through the line straight or diagonally: before[j] & after[j],
      // before[j-1] & after[j+1] or before[j+1] & after[j-1].
      const auto none = torch::zeros_like(line, torch::kBool);
      const auto before = i > 0 ? on.select(dim, i - 1) : none;
      const auto after = i + 1 < n ? on.select(dim, i + 1) : none;
      auto keep = before & after;
      const int64_t m = line.size(0);
      if (m > 2) {
        keep.slice(0, 1, m - 1).logical_or_(before.slice(0, 0, m - 2) & after.slice(0, 2, m));
        keep.slice(0, 1, m - 1).logical_or_(before.slice(0, 2, m) & after.slice(0, 0, m - 2));
      }
      line.copy_(torch::where(keep, line, zero));
    }
  };
  if (lines.row_period > 0) clear(0, lines.row_period, lines.row_offset);
  if (lines.col_period > 0) clear(1, lines.col_period, lines.col_offset);
  return edge.dim() == 3 ? e.unsqueeze(0) : e;
}

}  // namespace cgsr
