#pragma once
// `cgsr report RUN_DIRS... --out DIR`: collects the evaluations of run directories (results.json
// of `cgsr eval` or `cgsr run`) into report.md, report.csv and one PSNR-against-latency plot per
// scene and scale.

#include <CLI/CLI.hpp>

#include "cli/command.h"
#include "eval/report.h"

namespace cgsr::cli {

struct ReportOptions : RunSettings {
  std::vector<std::string> runs;  // run directories or results.json files (required)
};

config::Schema<ReportOptions> report_schema();
void setup_report(CLI::App& app);
// The report of the runs (eval/report.h).
nlohmann::ordered_json run_report(const ReportOptions& options, RunDir& run_dir);

}  // namespace cgsr::cli
