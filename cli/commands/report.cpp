#include "cli/commands/report.h"

#include <algorithm>
#include <cstdio>

#include "core/atomic_file.h"
#include "core/error.h"
#include "eval/pattern_choice.h"

namespace cgsr::cli {

config::Schema<ReportOptions> report_schema() {
  config::Schema<ReportOptions> s;
  s.field("runs", &ReportOptions::runs, "run directories or results.json files")
      .check([](const auto& v) { return !v.empty(); }, "needs at least one run directory");
  add_run_settings(s);
  return s;
}

std::vector<EvalResult> collect_evaluations(const std::vector<std::string>& runs) {
  std::vector<EvalResult> out;
  for (const auto& run : runs) {
    std::filesystem::path file(run);
    if (std::filesystem::is_directory(file)) file /= "results.json";
    nlohmann::ordered_json j;
    try {
      j = nlohmann::ordered_json::parse(read_file(file));
    } catch (const nlohmann::json::exception& e) {
      throw Error(file.string(), std::string("not valid JSON: ") + e.what());
    }
    if (!j.contains("evaluations") || !j["evaluations"].is_array())
      throw Error(file.string(), "has no 'evaluations' (is it the results of cgsr eval or cgsr run?)");
    for (size_t i = 0; i < j["evaluations"].size(); ++i)
      out.push_back(eval_result_from_json(j["evaluations"][i], file.string() + ": evaluations[" + std::to_string(i) + "]"));
  }
  return out;
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

nlohmann::ordered_json write_report(const std::vector<EvalResult>& evaluations, RunDir& run_dir,
                                    const std::vector<std::string>& heldout_scenes) {
  const auto tables = group_results(evaluations);
  std::string markdown;
  nlohmann::ordered_json results;
  results["tables"] = nlohmann::ordered_json::array();
  for (const auto& t : tables) {
    const bool heldout = std::find(heldout_scenes.begin(), heldout_scenes.end(), t.dataset) != heldout_scenes.end();
    if (heldout)
      markdown += "## Held-out scene: " + t.dataset +
                  "\n\nNot in the training data: how the networks do on content they never saw (quality only; "
                  "latency is the run's own table's).\n\n";
    markdown += report_markdown(t) + "\n";
    // A plot of PSNR against latency needs a latency (held-out scenes are evaluated for quality only).
    std::string plot;
    if (std::any_of(t.rows.begin(), t.rows.end(), [](const EvalResult& r) { return r.latency.has_value(); })) {
      plot = "plot_" + t.dataset + "_x" + std::to_string(t.scale) + ".png";
      write_report_plot(run_dir.file(plot), t);
      markdown += "![PSNR against latency](" + plot + ")\n\n";
    }
    results["tables"].push_back(
        {{"dataset", t.dataset}, {"scale", t.scale}, {"rows", t.rows.size()}, {"plot", plot}, {"heldout", heldout}});
    // Models that choose a pattern per frame: the choice next to each frame's edge density.
    for (size_t i = 0; i < t.rows.size(); ++i) {
      const auto choices = pattern_choices(t.rows[i]);
      if (!choices) continue;
      std::string choice_plot = "pattern_choice_" + t.dataset + "_x" + std::to_string(t.scale) + "_" +
                                std::to_string(i + 1) + ".png";
      const bool has_edges = std::any_of(choices->frames.begin(), choices->frames.end(),
                                         [](const FrameChoice& c) { return c.edge_fraction.has_value(); });
      if (has_edges)
        write_pattern_choice_plot(run_dir.file(choice_plot), t.rows[i].name, *choices);
      else
        choice_plot.clear();
      markdown += pattern_choice_markdown(t.rows[i].name, *choices, choice_plot);
      results["pattern_choices"].push_back(
          {{"model", t.rows[i].name}, {"patterns_used", choices->usage.size()}, {"plot", choice_plot}});
    }
  }
  write_file_atomic(run_dir.file("report.md"), markdown);
  write_file_atomic(run_dir.file("report.csv"), report_csv(tables));
  std::printf("%s", markdown.c_str());
  results["evaluations"] = nlohmann::ordered_json::array();
  for (const auto& e : evaluations) results["evaluations"].push_back(to_json(e));
  return results;
}

}  // namespace cgsr::cli
