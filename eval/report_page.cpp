#include "eval/report_page.h"

#include <algorithm>
#include <sstream>

#include "core/atomic_file.h"
#include "core/text.h"
#include "eval/frame_plot.h"
#include "eval/image_comparison.h"
#include "eval/pattern_choice.h"
#include "eval/report.h"

namespace cgsr {

std::string html_escape(const std::string& text) {
  std::string out;
  for (char c : text) switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += c;
    }
  return out;
}

namespace {
const char* kStyle = R"(
body { font-family: "DejaVu Sans", Verdana, sans-serif; margin: 24px auto; max-width: 1280px; color: #222; padding: 0 16px; }
h1 { font-size: 1.5em; } h2 { font-size: 1.2em; margin-top: 2em; border-bottom: 1px solid #ccc; } h3 { font-size: 1.05em; }
table { border-collapse: collapse; margin: 0.8em 0; font-size: 0.9em; }
th, td { border: 1px solid #ccc; padding: 3px 8px; } td.n { text-align: right; font-variant-numeric: tabular-nums; }
th.sortable { cursor: pointer; background: #f3f3f3; } th.sortable:hover { background: #e4e4e4; }
th.sorted-up::after { content: " \25B2"; } th.sorted-down::after { content: " \25BC"; }
tr.front td:first-child { font-weight: bold; } .pass { color: #16702c; } .fail { color: #b3151b; font-weight: bold; }
img { max-width: 100%; display: block; margin: 0.6em 0; } .note { color: #555; font-size: 0.9em; }
nav a { margin-right: 1em; }
)";

// Sorts a table by the clicked column: numbers (data-v) numerically, other cells as text.
const char* kScript = R"(
document.querySelectorAll('img').forEach(function (img) {
  img.addEventListener('error', function () { console.error('image not found: ' + img.getAttribute('src')); });
});
document.querySelectorAll('table.sortable').forEach(function (table) {
  table.querySelectorAll('th').forEach(function (th, column) {
    th.classList.add('sortable');
    th.addEventListener('click', function () {
      var up = !th.classList.contains('sorted-up');
      table.querySelectorAll('th').forEach(function (h) { h.classList.remove('sorted-up', 'sorted-down'); });
      th.classList.add(up ? 'sorted-up' : 'sorted-down');
      var body = table.tBodies[0];
      var rows = Array.prototype.slice.call(body.rows);
      rows.sort(function (a, b) {
        var x = a.cells[column].getAttribute('data-v'), y = b.cells[column].getAttribute('data-v');
        var r = (x !== null && y !== null) ? parseFloat(x) - parseFloat(y)
                                           : a.cells[column].textContent.localeCompare(b.cells[column].textContent);
        return up ? r : -r;
      });
      rows.forEach(function (row) { body.appendChild(row); });
    });
  });
});
)";

// A numeric cell: its text, and its value for sorting (cells without one sort first).
std::string number_cell(const ReportCell& cell) {
  return "<td class=\"n\" data-v=\"" + (cell.value ? fixed(*cell.value, 6) : std::string("-1e300")) + "\">" +
         html_escape(cell.text) + "</td>";
}

std::string table_html(const ReportTable& table) {
  std::ostringstream h;
  h << "<table class=\"sortable\"><thead><tr><th>Model</th>";
  for (const auto& c : report_columns(table)) h << "<th>" << html_escape(c) << "</th>";
  h << "</tr></thead><tbody>\n";
  const auto front = pareto_front(table);
  for (size_t i = 0; i < table.rows.size(); ++i) {
    const auto& r = table.rows[i];
    const bool on_front = std::find(front.begin(), front.end(), i) != front.end();
    h << "<tr" << (on_front ? " class=\"front\"" : "") << "><td>" << html_escape(r.name) << (on_front ? " *" : "")
      << "</td>";
    for (const auto& cell : report_row(r, table)) h << number_cell(cell);
    h << "</tr>\n";
  }
  h << "</tbody></table>\n";
  if (!front.empty())
    h << "<p class=\"note\">* on the Pareto front of PSNR against latency (bold). Click a column's title to sort. "
         "MACs at the evaluated LR size; latency is the median of repeated runs on this machine.</p>\n";
  return h.str();
}

std::string verdict_html(const nlohmann::ordered_json& verdict) {
  std::ostringstream h;
  int failed = 0;
  for (const auto& c : verdict.at("checks")) failed += c.at("passed").get<bool>() ? 0 : 1;
  h << "<h2 id=\"verdict\">Verdict: " << (failed == 0 ? "<span class=\"pass\">passed</span>"
                                                      : "<span class=\"fail\">" + std::to_string(failed) + " of " +
                                                            std::to_string(verdict.at("checks").size()) +
                                                            " checks failed</span>")
    << "</h2>\n<table class=\"sortable\"><thead><tr><th>Check</th><th>Result</th><th>Figures</th></tr></thead><tbody>\n";
  for (const auto& c : verdict.at("checks")) {
    const bool passed = c.at("passed").get<bool>();
    h << "<tr><td>" << html_escape(c.at("claim").get<std::string>()) << "</td><td class=\""
      << (passed ? "pass\">passed" : "fail\">failed") << "</td><td>" << html_escape(c.at("detail").get<std::string>())
      << "</td></tr>\n";
  }
  h << "</tbody></table>\n";
  return h.str();
}

std::string comparison_html(const ComparisonImage& image) {
  std::ostringstream h;
  h << "<h3>" << html_escape(image.dataset) << ", frame " << image.frame << "</h3>\n<p class=\"note\">Crop at x "
    << image.region.x << ", y " << image.region.y << " (" << image.region.width << " px square, HR); error colours run "
    << "from 0 to " << fixed(image.error_scale, 3) << " (absolute error, the same scale for every map).</p>\n"
    << "<img src=\"images/" << html_escape(image.crops) << "\" alt=\"crops of frame " << image.frame << "\">\n"
    << "<img src=\"images/" << html_escape(image.errors) << "\" alt=\"error maps of frame " << image.frame << "\">\n";
  return h.str();
}

std::string pattern_choice_html(const std::string& model, const PatternChoices& choices, const std::string& plot) {
  std::ostringstream h;
  h << "<h3>" << html_escape(model) << ": pattern per frame</h3>\n<p>" << html_escape(usage_text(choices))
    << ". Pattern 0 is the widest (the static network).</p>\n";
  if (!plot.empty()) h << "<img src=\"" << html_escape(plot) << "\" alt=\"pattern per frame\">\n";
  h << "<table class=\"sortable\"><thead><tr><th>Frame</th><th>Edge pixels (%)</th><th>Pattern</th>"
       "<th>Channels kept (%)</th><th>PSNR (dB)</th></tr></thead><tbody>\n";
  for (const auto& c : choices.frames)
    h << "<tr>" << number_cell({std::to_string(c.frame), c.frame})
      << number_cell(c.edge_fraction ? ReportCell{fixed(100.0 * *c.edge_fraction, 2), *c.edge_fraction}
                                     : ReportCell{"-", std::nullopt})
      << number_cell({std::to_string(c.pattern), c.pattern})
      << number_cell({fixed(100.0 * c.channel_fraction, 0), c.channel_fraction})
      << number_cell({fixed(c.psnr, 2), c.psnr}) << "</tr>\n";
  h << "</tbody></table>\n";
  return h.str();
}
}  // namespace

void write_report_page(const std::filesystem::path& dir, const nlohmann::ordered_json& report,
                       const nlohmann::ordered_json& verdict) {
  std::vector<EvalResult> evaluations;
  for (size_t i = 0; i < report.at("evaluations").size(); ++i)
    evaluations.push_back(eval_result_from_json(report["evaluations"][i], "report: evaluations[" + std::to_string(i) + "]"));
  const auto tables = group_results(evaluations);
  const auto list = [&](const char* key) { return report.contains(key) ? report[key] : nlohmann::ordered_json::array(); };
  const nlohmann::ordered_json table_meta = list("tables"), choice_meta = list("pattern_choices");
  std::vector<ComparisonImage> comparisons;
  for (const auto& c : list("comparisons")) comparisons.push_back(comparison_from_json(c, "report: comparisons"));

  std::ostringstream h;
  h << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>cgsr report</title>\n<style>"
    << kStyle << "</style></head><body>\n<h1>cgsr report</h1>\n<nav>";
  if (!verdict.is_null()) h << "<a href=\"#verdict\">verdict</a>";
  for (size_t t = 0; t < tables.size(); ++t)
    h << "<a href=\"#table" << t << "\">" << html_escape(tables[t].dataset) << " x" << tables[t].scale << "</a>";
  if (!comparisons.empty()) h << "<a href=\"#images\">image comparisons</a>";
  h << "</nav>\n";
  if (!verdict.is_null()) h << verdict_html(verdict);
  for (size_t t = 0; t < tables.size(); ++t) {
    const auto& table = tables[t];
    const auto& first = table.rows.front();
    const nlohmann::ordered_json* meta = nullptr;
    for (const auto& m : table_meta)
      if (m.value("dataset", "") == table.dataset && m.value("scale", 0) == table.scale &&
          m.value("target", "") == table.target)
        meta = &m;
    const bool heldout = meta && meta->value("heldout", false);
    h << "<h2 id=\"table" << t << "\">" << (heldout ? "Held-out scene: " : "") << html_escape(table.dataset) << " x"
      << table.scale << "</h2>\n<p class=\"note\">" << html_escape(first.split) << " split, " << first.frames.size()
      << " frames, LR " << first.lr_width << "x" << first.lr_height
      << (heldout ? "; not in the training data: quality only, latency is in the run's own table" : "")
      << (table.target.empty() ? "" : "; target: " + html_escape(table.target)) << ".</p>\n"
      << table_html(table);
    if (meta && !meta->value("plot_svg", "").empty())
      h << "<img src=\"" << html_escape(meta->value("plot_svg", "")) << "\" alt=\"PSNR against latency\">\n";
    if (meta && !meta->value("networks_plot_svg", "").empty())
      h << "<img src=\"" << html_escape(meta->value("networks_plot_svg", ""))
        << "\" alt=\"PSNR against latency, the networks\">\n";
    if (meta && !meta->value("frame_plot_svg", "").empty())
      h << "<h3>PSNR per frame</h3>\n<img src=\"" << html_escape(meta->value("frame_plot_svg", ""))
        << "\" alt=\"PSNR per frame\">\n<p class=\"note\">" << html_escape(psnr_per_frame_caption()) << "</p>\n";
    for (const auto& e : choice_meta) {
      if (e.value("dataset", "") != table.dataset || e.value("scale", 0) != table.scale ||
          e.value("target", "") != table.target)
        continue;
      const auto row = std::find_if(table.rows.begin(), table.rows.end(),
                                    [&](const EvalResult& r) { return r.name == e.value("model", ""); });
      if (row == table.rows.end()) continue;
      if (const auto choices = pattern_choices(*row)) h << pattern_choice_html(row->name, *choices, e.value("plot_svg", ""));
    }
  }
  if (!comparisons.empty()) {
    h << "<h2 id=\"images\">Image comparisons</h2>\n<p class=\"note\">The test frames with the most geometry-edge "
         "pixels and a frame of each held-out scene. The crop is where the networks differ most from bicubic.</p>\n";
    for (const auto& c : comparisons) h << comparison_html(c);
  }
  h << "<script>" << kScript << "</script>\n</body></html>\n";
  write_file_atomic(dir / "index.html", h.str());
}

}  // namespace cgsr
