#include "eval/frame_plot.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace cgsr {
namespace {
// One colour per model, in the order of the table's rows (repeating after the last): enough for
// the quickstart's report, whose tables have 12 rows.
const std::vector<Rgb> kColours = {{40, 90, 180},  {210, 40, 40},  {40, 150, 60},   {200, 130, 20},
                                   {130, 60, 170}, {110, 110, 110}, {20, 160, 170},  {180, 60, 130},
                                   {110, 80, 30},  {0, 0, 0},       {120, 190, 240}, {150, 200, 60}};

// The index into `starts` of the scene holding `frame`: the last one starting at or before it
// (0 when none does, or when there are no starts: one scene).
size_t scene_of(const std::vector<SceneStart>& starts, int frame) {
  size_t scene = 0;
  for (size_t i = 0; i < starts.size(); ++i)
    if (starts[i].first_frame <= frame) scene = i;
  return scene;
}

// The usual spacing of a row's evaluated frames within a scene: the median step (1 for a range
// of consecutive frames, about 10 for a test split); 1 when no two frames share a scene.
int usual_step(const EvalResult& row) {
  std::vector<int> steps;
  for (size_t i = 1; i < row.frames.size(); ++i) {
    const int a = row.frames[i - 1].frame, b = row.frames[i].frame;
    if (b > a && scene_of(row.scene_starts, a) == scene_of(row.scene_starts, b)) steps.push_back(b - a);
  }
  if (steps.empty()) return 1;
  std::nth_element(steps.begin(), steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2), steps.end());
  return steps[steps.size() / 2];
}
}  // namespace

std::optional<LinePlot> psnr_per_frame_plot(const ReportTable& table) {
  if (std::none_of(table.rows.begin(), table.rows.end(), [](const EvalResult& r) { return r.frames.size() >= 2; }))
    return std::nullopt;
  LinePlot plot;
  plot.title = table.dataset + " x" + std::to_string(table.scale) + ": PSNR per frame";
  plot.x_label = "frame (index in the data set)";
  plot.y_label = "PSNR (dB)";
  plot.integer_x = true;
  bool identical = false, sampled = false;
  for (size_t i = 0; i < table.rows.size(); ++i) {
    const EvalResult& row = table.rows[i];
    LineSeries s;
    s.name = row.name;
    s.colour = kColours[i % kColours.size()];
    const int step = usual_step(row);
    // A dot on every evaluated frame when they are samples of the sequence, or few.
    s.dots = step > 1 || row.frames.size() <= 30;
    sampled = sampled || step > 1;
    auto frames = row.frames;
    std::sort(frames.begin(), frames.end(), [](const FrameScore& a, const FrameScore& b) { return a.frame < b.frame; });
    for (size_t k = 0; k < frames.size(); ++k) {
      const int f = frames[k].frame;
      const bool joined = k > 0 && scene_of(row.scene_starts, frames[k - 1].frame) == scene_of(row.scene_starts, f) &&
                          f - frames[k - 1].frame <= 2 * step;
      if (!joined) s.segments.emplace_back();
      s.segments.back().push_back({double(f), frames[k].psnr});
      identical = identical || std::isinf(frames[k].psnr);
    }
    plot.series.push_back(std::move(s));
  }
  // The scenes of every row (rows of one table may come from different evaluations), by first frame.
  std::map<int, std::string> scenes;
  for (const auto& row : table.rows)
    for (const auto& s : row.scene_starts) scenes.emplace(s.first_frame, s.scene);
  for (const auto& [first, name] : scenes) plot.regions.push_back({double(first), name});
  if (plot.regions.size() > 1) plot.boundary_name = "scene cut (the history starts again)";
  if (sampled) plot.notes.push_back("dots: the evaluated frames");
  if (identical) plot.notes.push_back("hollow on the top edge: PSNR +inf (identical)");
  return plot;
}

std::string psnr_per_frame_plot_name(const std::string& table_stem) { return "psnr_per_frame_" + table_stem; }

std::string psnr_per_frame_caption() {
  return "PSNR of each evaluated frame, one line per model, against the frame's index in the data set. Dashed lines "
         "are scene cuts, where the history of temporal inputs starts again; no line crosses one, nor a stretch of "
         "frames that was not evaluated. An output identical to the ground truth (PSNR +inf) is a hollow marker on "
         "the top edge.";
}

}  // namespace cgsr
