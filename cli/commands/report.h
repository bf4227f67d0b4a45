#pragma once
// `cgsr report RUN_DIRS... --out DIR [--frames N]`: collects the evaluations of run directories
// (results.json of `cgsr eval` or `cgsr run`) into report.md, report.csv, index.html and one
// PSNR-against-latency plot per scene and scale; with --frames, image comparisons of the N
// frames with the most geometry edges of each eval run directory.

#include <CLI/CLI.hpp>

#include "cli/command.h"
#include "eval/report.h"

namespace cgsr::cli {

struct ReportOptions : RunSettings {
  std::vector<std::string> runs;  // run directories or results.json files (required)
  ComparisonOptions images = no_comparisons();  // image comparisons per eval run directory (none by default)
};

config::Schema<ReportOptions> report_schema();
void setup_report(CLI::App& app);
// The report of the runs (eval/report.h).
nlohmann::ordered_json run_report(const ReportOptions& options, RunDir& run_dir);

}  // namespace cgsr::cli
