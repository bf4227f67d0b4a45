#pragma once
// The error-against-run-time report: per scene and scale, one row per evaluated upscaler with
// Params (k), MACs (G), latency (ms, median on this machine), PSNR (with PSNR on geometry edges
// and on the rest when the results have them), SSIM and temporal error, as Markdown and CSV, plus a PNG plot of PSNR against latency with the Pareto front marked.
// Every value comes from evaluation results; nothing is typed in.
//
// The report of run directories (`cgsr report`, the report stage of `cgsr run`): the
// evaluations of their results.json files, collected, written as report.md, report.csv, a plot
// per table and its PSNR per frame (frame_plot.h), a pattern-choice section per model that
// chooses a pattern per frame (pattern_choice.h), image comparisons when given, and the same as
// one HTML page.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/plot.h"
#include "core/run_dir.h"
#include "eval/evaluation.h"
#include "eval/image_comparison.h"

namespace cgsr {

struct ReportTable {
  std::string dataset;
  int scale = 2;
  std::vector<EvalResult> rows;  // in the order given
  std::string target;            // the ground truth its rows measure against (EvalResult::target)
};

// Groups results by (dataset, scale, target), keeping their order within each group: a scene
// rendered aliased and supersampled is two tables.
std::vector<ReportTable> group_results(const std::vector<EvalResult>& results);

// The columns of a table after the model's name: latency only when some row was timed, ONNX
// Runtime only when some row has it, edge and rest PSNR only when some row has them.
std::vector<std::string> report_columns(const ReportTable& table);

// A row's figures in those columns, as printed ("-" or "NA" where there is none), with the value
// behind each for sorting (none where there is none).
struct ReportCell {
  std::string text;
  std::optional<double> value;
};
std::vector<ReportCell> report_row(const EvalResult& r, const ReportTable& table);

std::string report_markdown(const ReportTable& table);
std::string report_csv(const std::vector<ReportTable>& tables);

// The stem of table i's files ("<dataset>_x<scale>"): a scene and scale measured against another
// target too has tables of its own, "_2" and on.
std::string table_file_stem(const std::vector<ReportTable>& tables, size_t i);

// Indices of rows on the Pareto front: no other row is both faster and at least as good (PSNR).
std::vector<size_t> pareto_front(const ReportTable& table);

// Controls of one kind cut to several latencies: drawn as one line in a colour of its own, each
// point labelled short (the legend names the kind), so a kind's curve reads at a glance.
struct ReportCurve {
  std::string name;                                         // legend entry
  std::vector<std::pair<std::string, std::string>> points;  // (row name, its label on the plot)
};

// What rows are, for the plot: final networks and controls are drawn apart from the other
// networks, and each network is joined to its controls. Rows named in neither list are networks,
// or classic upscalers when they have no parameter count; a row on a curve is drawn on it.
struct ReportRoles {
  std::vector<std::string> finals, controls;
  std::vector<std::pair<std::string, std::string>> pairs;  // (network, one of its controls)
  std::vector<ReportCurve> curves;
};

// PSNR against latency, each point named; rows without latency are lines across the plot at
// their PSNR. `networks_only` leaves out the rows without a parameter count (classic upscalers),
// so the axes close in on the networks, which sit close together far from them.
ScatterPlot report_plot(const ReportTable& table, const ReportRoles& roles = {}, bool networks_only = false);

// Every evaluation found in the given run directories / results files (results.json of
// `cgsr eval`, `cgsr prune` or `cgsr report`), in order.
std::vector<EvalResult> collect_evaluations(const std::vector<std::string>& runs);

// Writes report.md, report.csv, index.html (report_page.h) and per (scene, scale) a plot of PSNR
// against latency and one of PSNR per frame (frame_plot.h), as PNG and SVG, into `run_dir`, and
// prints the tables; the results it returns carry the evaluations again, so a report can be
// reported on. The tables of `heldout_scenes` (data set names) are headed as scenes not in the
// training data. `comparisons` were written into run_dir/images (image_comparison.h).
nlohmann::ordered_json write_report(const std::vector<EvalResult>& evaluations, RunDir& run_dir,
                                    const std::vector<std::string>& heldout_scenes = {},
                                    const ReportRoles& roles = {},
                                    const std::vector<ComparisonImage>& comparisons = {});

}  // namespace cgsr
