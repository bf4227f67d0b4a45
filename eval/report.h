#pragma once
// The error-against-run-time report: per scene and scale, one row per evaluated upscaler with
// Params (k), MACs (G), latency (ms, median on this machine), PSNR (with PSNR on geometry edges
// and on the rest when the results have them), SSIM and temporal error, as Markdown and CSV, plus a PNG plot of PSNR against latency with the Pareto front marked.
// Every value comes from evaluation results; nothing is typed in.

#include <filesystem>
#include <string>
#include <vector>

#include "eval/evaluation.h"

namespace cgsr {

struct ReportTable {
  std::string dataset;
  int scale = 2;
  std::vector<EvalResult> rows;  // in the order given
};

// Groups results by (dataset, scale), keeping their order within each group.
std::vector<ReportTable> group_results(const std::vector<EvalResult>& results);

std::string report_markdown(const ReportTable& table);
std::string report_csv(const std::vector<ReportTable>& tables);

// Indices of rows on the Pareto front: no other row is both faster and at least as good (PSNR).
std::vector<size_t> pareto_front(const ReportTable& table);

// Writes a PSNR-against-latency scatter plot (PNG); rows without latency are drawn as lines
// across the plot at their PSNR.
void write_report_plot(const std::filesystem::path& path, const ReportTable& table);

}  // namespace cgsr
