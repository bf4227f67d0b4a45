#include "cli/commands/report.h"

namespace cgsr::cli {

config::Schema<ReportOptions> report_schema() {
  config::Schema<ReportOptions> s;
  s.field("runs", &ReportOptions::runs, "run directories or results.json files")
      .check([](const auto& v) { return !v.empty(); }, "needs at least one run directory");
  add_run_settings(s);
  return s;
}

void setup_report(CLI::App& app) {
  add_command<ReportOptions>(
      app, "report", "Tabulate and plot evaluations: quality against params, MACs and latency", report_schema,
      [](CLI::App& sub, std::vector<FlagAssignment>& flags) {
        list_to_key(sub, flags, "runs", "runs", "run directories or results.json files", "RUN_DIRS");
      },
      [](const ReportOptions& options, const YAML::Node&, RunDir* run_dir) { return run_report(options, *run_dir); },
      /*always_run_dir=*/true);
}

nlohmann::ordered_json run_report(const ReportOptions& options, RunDir& run_dir) {
  return write_report(collect_evaluations(options.runs), run_dir);
}

}  // namespace cgsr::cli
