#include "cli/commands/report.h"

#include "pipeline/eval_stage.h"

namespace cgsr::cli {

config::Schema<ReportOptions> report_schema() {
  config::Schema<ReportOptions> s;
  s.field("runs", &ReportOptions::runs, "run directories or results.json files")
      .check([](const auto& v) { return !v.empty(); }, "needs at least one run directory");
  s.section("images", &ReportOptions::images, comparison_schema_fields(),
            "crops and error maps of each eval run directory's frames with the most geometry edges");
  add_run_settings(s);
  return s;
}

void setup_report(CLI::App& app) {
  add_command<ReportOptions>(
      app, "report", "Tabulate and plot evaluations: quality against params, MACs and latency", report_schema,
      [](CLI::App& sub, std::vector<FlagAssignment>& flags) {
        list_to_key(sub, flags, "runs", "runs", "run directories or results.json files", "RUN_DIRS");
        flag_to_key(sub, flags, "--frames", "images.frames",
                    "image comparisons of the N frames with the most geometry edges of each eval run");
      },
      [](const ReportOptions& options, const YAML::Node&, RunDir* run_dir) { return run_report(options, *run_dir); },
      /*always_run_dir=*/true);
}

nlohmann::ordered_json run_report(const ReportOptions& options, RunDir& run_dir) {
  std::vector<ComparisonImage> comparisons;
  if (options.images.frames > 0)
    for (const auto& run : options.runs) {
      const auto more = compare_eval_run(run, options.images, run_dir.path() / "images");
      comparisons.insert(comparisons.end(), more.begin(), more.end());
    }
  return write_report(collect_evaluations(options.runs), run_dir, {}, {}, comparisons);
}

}  // namespace cgsr::cli
