#pragma once
// PSNR per frame over an evaluated sequence, one line per model of a report table, with the
// scene cuts marked: where a temporal upscaler's history starts again, so its warm-up after a cut
// and the frames where a model collapses can be seen. `cgsr eval` writes it next to results.json
// and the report page shows it under its table.
//
//   if (auto plot = psnr_per_frame_plot(table)) write_line_plot(dir / "psnr_per_frame.svg", *plot);

#include <optional>
#include <string>

#include "core/plot.h"
#include "eval/report.h"

namespace cgsr {

// Against the data set's frame index. A scene cut is a dashed line at the first frame of the
// scene that begins there (with every frame evaluated, its first evaluated frame; with a sampled
// split, the cut itself, so the distance to the first sample after it reads off). No line crosses
// a cut. Within a scene a line joins evaluated frames at their usual spacing (a test split's
// every 10th frame reads as a line, with a dot on each evaluated frame) and breaks where the
// spacing is more than twice the usual one: a line across frames nobody measured would show a
// trend that was not measured. PSNR +inf (an output identical to the ground truth) is a hollow
// marker on the top edge, said so in the legend. None when no row has two evaluated frames.
std::optional<LinePlot> psnr_per_frame_plot(const ReportTable& table);

// The file name of a table's plot without its extension, from the table's file stem
// (table_file_stem()).
std::string psnr_per_frame_plot_name(const std::string& table_stem);

// What the plot shows, for the caption under it in a page.
std::string psnr_per_frame_caption();

}  // namespace cgsr
