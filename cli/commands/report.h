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
nlohmann::ordered_json run_report(const ReportOptions& options, RunDir& run_dir);
// Writes report.md, report.csv and one plot per (scene, scale) into `run_dir` and prints the
// tables; the results it returns carry the evaluations again, so a report can be reported on.
// The tables of `heldout_scenes` (data set names) are headed as scenes not in the training data.
nlohmann::ordered_json write_report(const std::vector<EvalResult>& evaluations, RunDir& run_dir,
                                    const std::vector<std::string>& heldout_scenes = {});

// Every evaluation found in the given run directories / results files, in order.
std::vector<EvalResult> collect_evaluations(const std::vector<std::string>& runs);

}  // namespace cgsr::cli
