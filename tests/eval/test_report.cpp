// The report: Pareto front, tables, CSV and plot from evaluation results.
#include <gtest/gtest.h>

#include <filesystem>

#include "core/atomic_file.h"
#include "eval/report.h"

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
  const auto dir = std::filesystem::temp_directory_path() / "cgsr-report-plot";
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
