#pragma once
// Removal of the periodic tile-grid lines that the GPU simulator behind the CGSR data release
// leaves in its edge masks: whole rows/columns of "edges" repeating every p pixels.
//
// Detection, separately for rows and columns of one edge mask: the edge density of each row is
// compared over every period p in [4, size/3] and offset o; the grid is the (smallest) (p, o)
// whose rows are dense (mean density >= min_line_density) and anomalously denser than the
// other rows (>= contrast x their mean + 0.1), found in at least 3 lines. Clean-up clears the
// grid lines except where a genuine edge crosses them: edge pixels (off the grid) on both sides
// of the line, straight across or diagonally opposite.

#include <torch/types.h>

namespace cgsr {

struct GridLines {
  int row_period = 0, row_offset = 0;  // period 0: no row grid found
  int col_period = 0, col_offset = 0;
  bool found() const { return row_period > 0 || col_period > 0; }
};

struct GridLineSettings {
  double min_line_density = 0.5;  // fraction of a line's pixels that are edges
  double contrast = 3.0;          // grid lines vs. the other lines' mean density
};

// edge: [1,H,W] or [H,W], values 0/1 (any dtype).
GridLines detect_grid_lines(const torch::Tensor& edge, const GridLineSettings& settings = {});
// Returns a cleaned copy (same shape and dtype).
torch::Tensor remove_grid_lines(const torch::Tensor& edge, const GridLines& lines);

}  // namespace cgsr
