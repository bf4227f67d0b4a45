// The report: Pareto front, tables, CSV and plot from evaluation results, and PSNR per frame
// (lines broken at scene cuts and missing frames, infinite PSNR drawn on the edge).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/run_dir.h"
#include "eval/frame_plot.h"
#include "eval/report.h"
#include "tests/support/svg_paths.h"
#include "tests/support/scratch_dir.h"

using namespace cgsr;

namespace {
EvalResult row(const std::string& name, double psnr, std::optional<double> ms, std::optional<int64_t> params = {}) {
  EvalResult r;
  r.name = name;
  r.dataset = "hall";
  r.split = "test";
  r.scale = 2;
  r.psnr = psnr;
  r.ssim = 0.9;
  r.frames.resize(3);
  if (ms) {
    LatencyStats l;
    l.median_ms = *ms;
    r.latency = l;
  }
  if (params) {
    Complexity c;
    c.params = *params;
    c.macs = *params * 1000;
    r.cost = c;
  }
  return r;
}
}  // namespace

TEST(Report, ParetoFrontKeepsOnlyUndominatedRows) {
  ReportTable t{"hall", 2, {row("fast", 30, 1.0), row("slow-worse", 29, 5.0), row("slow-better", 33, 10.0),
                            row("no-latency", 40, std::nullopt)}, ""};
  EXPECT_EQ(pareto_front(t), (std::vector<size_t>{0, 2}));
}

TEST(Report, GroupsByDatasetAndScale) {
  auto a = row("a", 30, 1.0), b = row("b", 31, 2.0), c = row("c", 32, 3.0);
  c.scale = 3;
  const auto tables = group_results({a, c, b});
  ASSERT_EQ(tables.size(), 2u);
  EXPECT_EQ(tables[0].rows.size(), 2u);
  EXPECT_EQ(tables[1].scale, 3);
}

TEST(Report, MarkdownAndCsvCarryTheComputedValues) {
  ReportTable t{"hall", 2, {row("bicubic", 30.123, 0.5), row("pan", 33.456, 12.0, 261403)}, ""};
  const auto md = report_markdown(t);
  EXPECT_NE(md.find("| bicubic * | NA | NA | 0.50 | 30.12 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| pan * | 261.4 | 0.26 | 12.00 | 33.46 |"), std::string::npos) << md;
  const auto csv = report_csv({t});
  EXPECT_NE(csv.find("hall,2,pan,261403,261403000,12.0000,33.4560"), std::string::npos) << csv;
}

TEST(Report, CsvQuotesNamesWithCommasAndQuotes) {
  ReportTable t{"hall, east", 2, {row("PAN x2 (keep 0.5, \"wide\")", 33.456, 12.0)}, ""};
  const auto csv = report_csv({t});
  EXPECT_NE(csv.find("\n\"hall, east\",2,\"PAN x2 (keep 0.5, \"\"wide\"\")\",,,12.0000,33.4560"), std::string::npos)
      << csv;
}

TEST(Report, ALatencyColumnOnlyWhenSomeRowWasTimed) {
  // A held-out scene is evaluated for quality only: no latency column, no Pareto front.
  ReportTable t{"hall", 2, {row("bicubic", 30.123, std::nullopt), row("pan", 33.456, std::nullopt, 261403)}, ""};
  const auto md = report_markdown(t);
  EXPECT_NE(md.find("| Model | Params (k) | MACs (G) | PSNR (dB) | SSIM |"), std::string::npos) << md;
  EXPECT_NE(md.find("| pan | 261.4 | 0.26 | 33.46 | 0.9000 |"), std::string::npos) << md;
  EXPECT_EQ(md.find("Latency"), std::string::npos) << md;
  EXPECT_EQ(md.find("Pareto"), std::string::npos) << md;
}

TEST(Report, EdgeColumnsOnlyWhenSomeRowHasThem) {
  ReportTable plain{"hall", 2, {row("bicubic", 30.123, 0.5), row("pan", 33.456, 12.0, 261403)}, ""};
  EXPECT_EQ(report_markdown(plain).find("Edge PSNR"), std::string::npos);

  auto pan = row("pan", 33.456, 12.0, 261403);
  pan.psnr_edge = 27.891;
  pan.psnr_rest = 34.012;
  pan.edge_fraction = 0.0731;
  ReportTable t{"hall", 2, {row("bicubic", 30.123, 0.5), pan}, ""};  // bicubic: an older result without them
  const auto md = report_markdown(t);
  EXPECT_NE(md.find("| PSNR (dB) | Edge PSNR (dB) | Rest PSNR (dB) | SSIM |"), std::string::npos) << md;
  EXPECT_NE(md.find("|---|---:|---:|---:|---:|---:|---:|---:|---:|\n"), std::string::npos) << md;
  EXPECT_NE(md.find("| pan * | 261.4 | 0.26 | 12.00 | 33.46 | 27.89 | 34.01 | 0.9000 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| bicubic * | NA | NA | 0.50 | 30.12 | - | - | 0.9000 |"), std::string::npos) << md;
  EXPECT_NE(md.find("(7.3% of the pixels)"), std::string::npos) << md;

  const auto csv = report_csv({t});
  EXPECT_NE(csv.find("onnxruntime_latency_ms,psnr_edge,psnr_rest,edge_fraction,target\n"), std::string::npos) << csv;
  EXPECT_NE(csv.find(",27.8910,34.0120,0.073100,\n"), std::string::npos) << csv;  // no target: an older result
  EXPECT_NE(csv.find("hall,2,bicubic,"), std::string::npos) << csv;
  EXPECT_NE(csv.find(",,,,\n"), std::string::npos) << csv;  // bicubic: no ONNX Runtime, no edge figures
}

TEST(Report, PlotIsAPngAndAnSvg) {
  const auto dir = test::scratch_dir("report-plot");
  auto pan = row("pan", 33, 12.0, 261403);
  pan.psnr_edge = 28;
  ReportTable t{"hall", 2, {row("bicubic", 30, 0.5), pan, row("fsr", 31, std::nullopt)}, ""};
  write_scatter_plot(dir / "plot.png", report_plot(t));
  write_scatter_plot(dir / "plot.svg", report_plot(t));
  const auto png = read_file(dir / "plot.png"), svg = read_file(dir / "plot.svg");
  ASSERT_GT(png.size(), 1000u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
  EXPECT_NE(svg.find("<svg"), std::string::npos);
  std::filesystem::remove_all(dir);
}

// Controls and final networks are drawn apart, each pair is joined, and every timed row is a
// point named after its model.
TEST(Report, PlotMarksRolesAndJoinsPairs) {
  ReportTable t{"hall", 2,
                {row("bicubic", 30, 0.5), row("pan", 33, 12.0, 261403), row("pan (control)", 33.1, 12.1, 261403),
                 row("pan cg", 33.3, 12.5, 270000), row("slim", 33.2, 4.0, 70000)}, ""};
  ReportRoles roles;
  roles.finals = {"slim"};
  roles.controls = {"pan (control)"};
  roles.pairs = {{"pan cg", "pan (control)"}, {"slim", "missing row"}};
  const ScatterPlot plot = report_plot(t, roles);
  std::map<std::string, std::string> series_of;
  for (const auto& s : plot.series)
    for (const auto& p : s.points)
      if (!p.label.empty()) series_of[p.label] = s.name;
  EXPECT_EQ(series_of.size(), 5u);
  EXPECT_EQ(series_of["bicubic"], "classic upscaler");
  EXPECT_EQ(series_of["pan"], "network");
  EXPECT_EQ(series_of["pan (control)"], "control");
  EXPECT_EQ(series_of["slim"], "final network");
  ASSERT_EQ(plot.links.size(), 1u);  // a pair with a missing row is left out
  EXPECT_DOUBLE_EQ(plot.links[0].x0, 12.5);
  EXPECT_DOUBLE_EQ(plot.links[0].x1, 12.1);
}

// A control kind cut to several latencies is one line of its own, its points labelled short;
// the other rows keep their series.
TEST(Report, PlotDrawsEachCurveAsALine) {
  ReportTable t{"hall", 2,
                {row("pan cg", 33.3, 12.5, 270000), row("slim", 33.2, 4.0, 70000), row("mmp", 32.9, 4.1, 90000),
                 row("mmp at 1.5x", 33.1, 6.0, 120000), row("uniform", 33.0, 4.0, 60000)}, ""};
  ReportRoles roles;
  roles.finals = {"slim"};
  roles.controls = {"mmp", "mmp at 1.5x", "uniform"};
  roles.curves = {{"MMP control", {{"mmp", "MMP 1x"}, {"mmp at 1.5x", "MMP 1.5x"}, {"not timed", "MMP 2x"}}}};
  const ScatterPlot plot = report_plot(t, roles);
  const auto curve = std::find_if(plot.series.begin(), plot.series.end(),
                                  [](const PlotSeries& s) { return s.name == "MMP control"; });
  ASSERT_NE(curve, plot.series.end());
  EXPECT_TRUE(curve->connect);
  ASSERT_EQ(curve->points.size(), 2u);  // a curve's row missing from the table is left out
  EXPECT_EQ(curve->points[0].label, "MMP 1x");
  EXPECT_DOUBLE_EQ(curve->points[0].x, 4.1);
  EXPECT_EQ(curve->points[1].label, "MMP 1.5x");
  EXPECT_DOUBLE_EQ(curve->points[1].y, 33.1);
  for (const auto& s : plot.series)
    for (const auto& p : s.points) {
      if (p.label == "uniform") {
        EXPECT_EQ(s.name, "control");
      }
      if (p.label == "slim") {
        EXPECT_EQ(s.name, "final network");
      }
      EXPECT_NE(p.label, "mmp") << s.name;  // drawn on the curve only, under its short label
    }
  EXPECT_EQ(plot.series.back().name, "final network");  // drawn last, on top
}

// With classic upscalers timed beside two networks, the networks get a second plot of their own
// (no classic row on it), in the results, the Markdown and the page; without them, none.
TEST(Report, WriteReportZoomsOnTheNetworks) {
  const auto dir = test::scratch_dir("report-zoom");
  {
    RunDir run(dir, /*own_log=*/false);
    const ReportTable t{"hall", 2, {row("bicubic", 30, 0.5), row("pan", 33, 12.0, 261403), row("slim", 32.9, 4.0, 70000)}, ""};
    for (const auto& s : report_plot(t, {}, true).series) EXPECT_NE(s.name, "classic upscaler");
    const auto results = write_report(t.rows, run);
    EXPECT_EQ(results["tables"][0].at("networks_plot"), "plot_hall_x2_networks.png");
    const std::string md = read_file(dir / "report.md"), page = read_file(dir / "index.html");
    EXPECT_NE(md.find("(plot_hall_x2_networks.png)"), std::string::npos) << md;
    EXPECT_NE(page.find("<img src=\"plot_hall_x2_networks.svg\""), std::string::npos) << page;
    const auto networks_only = write_report({row("pan", 33, 12.0, 261403), row("slim", 32.9, 4.0, 70000)}, run);
    EXPECT_EQ(networks_only["tables"][0].at("networks_plot"), "");
  }
  EXPECT_TRUE(std::filesystem::exists(dir / "plot_hall_x2_networks.png"));
  EXPECT_TRUE(std::filesystem::exists(dir / "plot_hall_x2_networks.svg"));
  std::filesystem::remove_all(dir);
}

namespace {
// A row scored on `frames`, PSNR 30 + frame / 100 (+inf on `identical`), in scenes starting at
// the given (name, first frame).
EvalResult scored(const std::string& name, const std::vector<int>& frames, std::vector<SceneStart> scenes,
                  const std::vector<int>& identical = {}) {
  EvalResult r = row(name, 30, 1.0);
  r.frames.clear();
  for (int f : frames) {
    FrameScore s;
    s.frame = f;
    s.psnr = std::find(identical.begin(), identical.end(), f) != identical.end() ? INFINITY : 30 + f / 100.0;
    r.frames.push_back(s);
  }
  r.scene_starts = std::move(scenes);
  return r;
}

std::vector<std::vector<double>> segment_xs(const LineSeries& s) {
  std::vector<std::vector<double>> out;
  for (const auto& segment : s.segments) {
    out.emplace_back();
    for (const auto& p : segment) out.back().push_back(p.x);
  }
  return out;
}
}  // namespace

// Consecutive frames: a line per scene, broken where frames 8 and 9 were not evaluated.
TEST(Report, PsnrPerFrameBreaksAtSceneCutsAndMissingFrames) {
  const std::vector<SceneStart> scenes = {{"hall", 0}, {"yard", 6}};
  ReportTable t{"set", 2, {scored("bicubic", {0, 1, 2, 3, 4, 5, 6, 7, 10, 11}, scenes),
                           scored("pan", {0, 1, 2, 3, 4, 5, 6, 7, 10, 11}, scenes)}, ""};
  const auto plot = psnr_per_frame_plot(t);
  ASSERT_TRUE(plot.has_value());
  ASSERT_EQ(plot->series.size(), 2u);
  for (const auto& s : plot->series)
    EXPECT_EQ(segment_xs(s), (std::vector<std::vector<double>>{{0, 1, 2, 3, 4, 5}, {6, 7}, {10, 11}})) << s.name;
  EXPECT_NE(plot->series[0].colour, plot->series[1].colour);
  ASSERT_EQ(plot->regions.size(), 2u);
  EXPECT_EQ(plot->regions[1].start, 6);
  EXPECT_EQ(plot->regions[1].name, "yard");
  EXPECT_FALSE(plot->boundary_name.empty());
}

// A test split samples every 10th frame or so: those are joined within a scene, with a dot on
// each, and the cut is drawn where the second scene begins, before its first sample.
TEST(Report, PsnrPerFrameJoinsTheSamplesOfASplitWithinAScene) {
  ReportTable t{"set", 2, {scored("bicubic", {4, 14, 25, 35, 46, 56, 86}, {{"hall", 0}, {"yard", 40}})}, ""};
  const auto plot = psnr_per_frame_plot(t);
  ASSERT_TRUE(plot.has_value());
  // 86 is 30 frames after 56: more than twice the usual step of 10, a stretch nobody measured.
  EXPECT_EQ(segment_xs(plot->series[0]), (std::vector<std::vector<double>>{{4, 14, 25, 35}, {46, 56}, {86}}));
  EXPECT_TRUE(plot->series[0].dots);
  EXPECT_EQ(plot->regions[1].start, 40);
}

TEST(Report, NoPsnrPerFrameForASingleFrame) {
  ReportTable one{"set", 2, {scored("bicubic", {3}, {{"hall", 0}}), scored("pan", {3}, {{"hall", 0}})}, ""};
  EXPECT_FALSE(psnr_per_frame_plot(one).has_value());
  // Results from before scene starts were recorded: one scene, no cut.
  ReportTable old{"set", 2, {scored("bicubic", {3, 4}, {})}, ""};
  const auto plot = psnr_per_frame_plot(old);
  ASSERT_TRUE(plot.has_value());
  EXPECT_TRUE(plot->regions.empty());
  EXPECT_TRUE(plot->boundary_name.empty());
  EXPECT_EQ(plot->series[0].segments.size(), 1u);
}

// Frames whose output equals the ground truth have PSNR +inf: drawn on the top edge and said so,
// with every coordinate of the SVG finite, also when every frame of a model is identical.
TEST(Report, InfinitePsnrPerFrameStaysOnThePlot) {
  const std::vector<SceneStart> scenes = {{"hall", 0}};
  ReportTable t{"set", 2,
                {scored("nearest", {0, 1, 2, 3}, scenes, {2}), scored("copy", {0, 1, 2, 3}, scenes, {0, 1, 2, 3})}, ""};
  const auto plot = psnr_per_frame_plot(t);
  ASSERT_TRUE(plot.has_value());
  EXPECT_TRUE(std::any_of(plot->notes.begin(), plot->notes.end(),
                          [](const std::string& n) { return n.find("+inf") != std::string::npos; }));
  const auto canvas = draw_line_plot(*plot);
  const auto dir = test::scratch_dir("report-frame-plot");
  canvas->save(dir / "frames.svg");
  const auto paths = test::svg_paths(read_file(dir / "frames.svg"));
  ASSERT_FALSE(paths.empty());
  size_t numbers = 0;
  for (const auto& p : paths)
    for (const auto& n : p.numbers) {
      ++numbers;
      EXPECT_TRUE(std::isfinite(std::stod(n))) << n;
    }
  EXPECT_GT(numbers, 100u);
  // nearest's line runs through its infinite frame, on the top edge of the plot area: the frame
  // drawn round it (Cairo would turn an infinite coordinate into some finite one, so the test
  // checks where the point is).
  const auto stroked = [&](const Rgb& colour) {
    std::vector<test::SvgPath> out;
    for (const auto& p : paths)
      if (p.stroked && p.straight && !p.dashed && p.stroke == colour) out.push_back(p);
    return out;
  };
  const auto frame = stroked({60, 60, 60});
  ASSERT_EQ(frame.size(), 1u);
  const double top = *std::min_element(frame[0].ys.begin(), frame[0].ys.end());
  const double right = *std::max_element(frame[0].xs.begin(), frame[0].xs.end());
  // A model's lines inside the frame (its legend sample is right of it).
  const auto lines = [&](const Rgb& colour) {
    std::vector<test::SvgPath> out;
    for (const auto& p : stroked(colour))
      if (*std::max_element(p.xs.begin(), p.xs.end()) < right) out.push_back(p);
    return out;
  };
  const auto nearest = lines(plot->series[0].colour);
  ASSERT_EQ(nearest.size(), 1u);
  ASSERT_EQ(nearest[0].ys.size(), 4u);
  EXPECT_NEAR(nearest[0].ys[2], top, 0.01);
  EXPECT_GT(std::min({nearest[0].ys[0], nearest[0].ys[1], nearest[0].ys[3]}), top + 10);
  const auto copy = lines(plot->series[1].colour);  // along the edge (Cairo merges its collinear points)
  ASSERT_EQ(copy.size(), 1u);
  for (double y : copy[0].ys) EXPECT_NEAR(y, top, 0.01);
  std::filesystem::remove_all(dir);
}

// The report draws PSNR per frame under each table with two evaluated frames, records it in its
// results and shows it on its page.
TEST(Report, WriteReportDrawsPsnrPerFrame) {
  const auto dir = test::scratch_dir("report-frames");
  auto single = scored("bicubic", {3}, {{"yard", 0}});
  single.dataset = "yard";
  {
    RunDir run(dir, /*own_log=*/false);
    const auto results =
        write_report({scored("bicubic", {0, 1, 2}, {{"hall", 0}}), scored("pan", {0, 1, 2}, {{"hall", 0}}), single}, run);
    ASSERT_EQ(results.at("tables").size(), 2u);
    EXPECT_EQ(results["tables"][0].at("frame_plot_svg"), "psnr_per_frame_hall_x2.svg");
    EXPECT_EQ(results["tables"][0].at("frame_plot"), "psnr_per_frame_hall_x2.png");
    EXPECT_EQ(results["tables"][1].at("frame_plot_svg"), "");  // one frame: nothing to draw
  }
  EXPECT_TRUE(std::filesystem::exists(dir / "psnr_per_frame_hall_x2.svg"));
  EXPECT_TRUE(std::filesystem::exists(dir / "psnr_per_frame_hall_x2.png"));
  EXPECT_FALSE(std::filesystem::exists(dir / "psnr_per_frame_yard_x2.svg"));
  const std::string page = read_file(dir / "index.html"), md = read_file(dir / "report.md");
  EXPECT_NE(page.find("<img src=\"psnr_per_frame_hall_x2.svg\""), std::string::npos) << page;
  EXPECT_EQ(page.find("psnr_per_frame_yard"), std::string::npos);
  EXPECT_NE(md.find("(psnr_per_frame_hall_x2.png)"), std::string::npos) << md;
  std::filesystem::remove_all(dir);
}

// Scene starts go through results.json and back (the report redraws the cuts from it).
TEST(Report, SceneStartsSurviveJson) {
  const auto r = scored("bicubic", {0, 7}, {{"hall", 0}, {"yard", 6}});
  const auto back = eval_result_from_json(to_json(r), "test");
  ASSERT_EQ(back.scene_starts.size(), 2u);
  EXPECT_EQ(back.scene_starts[1].scene, "yard");
  EXPECT_EQ(back.scene_starts[1].first_frame, 6);
  auto old = to_json(r);
  old.erase("scene_starts");
  EXPECT_TRUE(eval_result_from_json(old, "test").scene_starts.empty());
  old["scene_starts"] = {{{"scene", "hall"}}};
  EXPECT_THROW(eval_result_from_json(old, "results.json: evaluations[0]"), Error);
}
