#include "eval/report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/pareto.h"
#include "core/text.h"
#include "eval/frame_plot.h"
#include "eval/pattern_choice.h"
#include "eval/report_page.h"

namespace cgsr {
namespace {
// A CSV field as RFC 4180 writes it: quoted when it holds a comma, a quote or a line break.
std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\r\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

std::string optional_fixed(std::optional<double> v, int digits, const std::string& none) {
  return v ? fixed(*v, digits) : none;
}

// Which optional columns a table prints.
struct Shown {
  bool latency, onnxruntime, edges;
};
Shown shown(const ReportTable& table) {
  const auto any = [&](auto has) { return std::any_of(table.rows.begin(), table.rows.end(), has); };
  return {any([](const EvalResult& r) { return r.latency.has_value(); }),
          any([](const EvalResult& r) { return r.onnxruntime_latency.has_value(); }),
          any([](const EvalResult& r) { return r.psnr_edge || r.psnr_rest; })};
}
}  // namespace

std::vector<std::string> report_columns(const ReportTable& table) {
  const Shown s = shown(table);
  std::vector<std::string> columns = {"Params (k)", "MACs (G)"};
  if (s.latency) columns.push_back("Latency (ms)");
  if (s.onnxruntime) columns.push_back("ONNX Runtime (ms)");
  columns.push_back("PSNR (dB)");
  if (s.edges) columns.insert(columns.end(), {"Edge PSNR (dB)", "Rest PSNR (dB)"});
  columns.insert(columns.end(), {"SSIM", "Temporal error (x1e-3)"});
  return columns;
}

std::vector<ReportCell> report_row(const EvalResult& r, const ReportTable& table) {
  const Shown s = shown(table);
  const auto ms = [](const std::optional<LatencyStats>& l) {
    return l ? ReportCell{fixed(l->median_ms, 2), l->median_ms} : ReportCell{"-", std::nullopt};
  };
  const auto optional = [](std::optional<double> v, double factor, int digits) {
    return v ? ReportCell{fixed(*v * factor, digits), *v} : ReportCell{"-", std::nullopt};
  };
  std::vector<ReportCell> row;
  row.push_back(r.cost ? ReportCell{fixed(r.cost->params / 1000.0, 1), double(r.cost->params)} : ReportCell{"NA", {}});
  row.push_back(r.cost ? ReportCell{fixed(r.cost->macs / 1e9, 2), double(r.cost->macs)} : ReportCell{"NA", {}});
  if (s.latency) row.push_back(ms(r.latency));
  if (s.onnxruntime) row.push_back(ms(r.onnxruntime_latency));
  row.push_back({fixed(r.psnr, 2), r.psnr});
  if (s.edges) row.insert(row.end(), {optional(r.psnr_edge, 1, 2), optional(r.psnr_rest, 1, 2)});
  row.push_back({fixed(r.ssim, 4), r.ssim});
  row.push_back(optional(r.temporal_error, 1000.0, 2));
  return row;
}

std::vector<ReportTable> group_results(const std::vector<EvalResult>& results) {
  std::vector<ReportTable> tables;
  for (const auto& r : results) {
    auto it = std::find_if(tables.begin(), tables.end(),
                           [&](const ReportTable& t) {
                             return t.dataset == r.dataset && t.scale == r.scale && t.target == r.target;
                           });
    if (it == tables.end()) {
      tables.push_back({r.dataset, r.scale, {}, r.target});
      it = tables.end() - 1;
    }
    it->rows.push_back(r);
  }
  return tables;
}

std::string table_file_stem(const std::vector<ReportTable>& tables, size_t i) {
  const ReportTable& t = tables.at(i);
  const auto same = std::count_if(tables.begin(), tables.begin() + static_cast<std::ptrdiff_t>(i),
                                  [&](const ReportTable& o) { return o.dataset == t.dataset && o.scale == t.scale; });
  return t.dataset + "_x" + std::to_string(t.scale) + (same ? "_" + std::to_string(same + 1) : "");
}

std::vector<size_t> pareto_front(const ReportTable& table) {
  std::vector<size_t> timed;  // rows without latency are on no front
  std::vector<double> latency, psnr;
  for (size_t i = 0; i < table.rows.size(); ++i)
    if (table.rows[i].latency) {
      timed.push_back(i);
      latency.push_back(table.rows[i].latency->median_ms);
      psnr.push_back(table.rows[i].psnr);
    }
  std::vector<size_t> front;
  for (size_t k : cgsr::pareto_front(latency, psnr)) front.push_back(timed[k]);
  return front;
}

std::string report_markdown(const ReportTable& table) {
  std::ostringstream md;
  const auto& first = table.rows.front();
  md << "### " << table.dataset << " x" << table.scale << " (" << first.split << " split, " << first.frames.size()
     << " frames, LR " << first.lr_width << "x" << first.lr_height << ")\n\n";
  if (!table.target.empty()) md << "Target: " << table.target << ".\n\n";
  const auto columns = report_columns(table);
  md << "| Model |";
  for (const auto& c : columns) md << " " << c << " |";
  md << "\n|---|";
  for (size_t i = 0; i < columns.size(); ++i) md << "---:|";
  md << "\n";
  const auto front = pareto_front(table);
  for (size_t i = 0; i < table.rows.size(); ++i) {
    const auto& r = table.rows[i];
    const bool on_front = std::find(front.begin(), front.end(), i) != front.end();
    md << "| " << r.name << (on_front ? " *" : "") << " |";
    for (const auto& cell : report_row(r, table)) md << " " << cell.text << " |";
    md << "\n";
  }
  const Shown s = shown(table);
  const bool timed = s.latency, ort = s.onnxruntime, edges = s.edges;
  // Edge and rest PSNR need the dataset's edge channel; rows from older results lack them.
  const auto with_edges = std::find_if(table.rows.begin(), table.rows.end(),
                                       [](const EvalResult& r) { return r.psnr_edge || r.psnr_rest; });
  if (first.temporal_error_reference)
    md << "\nTemporal error of the ground truth (the floor): " << fixed(*first.temporal_error_reference * 1000.0, 2)
       << "e-3. ";
  if (timed)
    md << "\n* on the Pareto front of PSNR against latency. MACs at the evaluated LR size; latency is the median "
          "of repeated runs on this machine"
       << (ort ? " (cgsr's own inference; ONNX Runtime: the exported file on the same input)" : "") << ".\n";
  else
    md << "\nMACs at the evaluated LR size.\n";
  if (edges) {
    md << "Edge PSNR: on the HR geometry-edge pixels grown by one pixel";
    if (with_edges->edge_fraction) md << " (" << fixed(100.0 * *with_edges->edge_fraction, 1) << "% of the pixels)";
    md << "; Rest PSNR: on the other pixels.\n";
  }
  return md.str();
}

std::string report_csv(const std::vector<ReportTable>& tables) {
  std::ostringstream csv;
  csv << "dataset,scale,model,params,macs,latency_ms,psnr,ssim,temporal_error,temporal_error_reference,frames,"
         "onnxruntime_latency_ms,psnr_edge,psnr_rest,edge_fraction,target\n";
  for (const auto& t : tables)
    for (const auto& r : t.rows) {
      csv << csv_field(t.dataset) << "," << t.scale << "," << csv_field(r.name) << ","
          << (r.cost ? std::to_string(r.cost->params) : "") << ","
          << (r.cost ? std::to_string(r.cost->macs) : "") << ","
          << (r.latency ? fixed(r.latency->median_ms, 4) : "") << "," << fixed(r.psnr, 4) << "," << fixed(r.ssim, 6)
          << "," << (r.temporal_error ? fixed(*r.temporal_error, 6) : "") << ","
          << (r.temporal_error_reference ? fixed(*r.temporal_error_reference, 6) : "") << "," << r.frames.size() << ","
          << (r.onnxruntime_latency ? fixed(r.onnxruntime_latency->median_ms, 4) : "") << ","
          << optional_fixed(r.psnr_edge, 4, "") << "," << optional_fixed(r.psnr_rest, 4, "") << ","
          << optional_fixed(r.edge_fraction, 6, "") << "," << csv_field(t.target) << "\n";
    }
  return csv.str();
}

ScatterPlot report_plot(const ReportTable& table, const ReportRoles& roles, bool networks_only) {
  ScatterPlot plot;
  plot.title = table.dataset + " x" + std::to_string(table.scale) + ": PSNR against latency" +
               (networks_only ? ", the networks" : "");
  plot.x_label = "latency (ms, median, log scale)";
  plot.y_label = "PSNR (dB)";
  plot.log_x = true;
  auto named = [](const std::vector<std::string>& names, const std::string& name) {
    return std::find(names.begin(), names.end(), name) != names.end();
  };
  PlotSeries classic{"classic upscaler", {120, 120, 120}, 5, false, Marker::Triangle, true, {}};
  PlotSeries network{"network", {40, 90, 180}, 5, false, Marker::Circle, true, {}};
  PlotSeries control{"control", {40, 90, 180}, 5, false, Marker::Square, false, {}};
  PlotSeries final_net{"final network", {210, 40, 40}, 6.5, false, Marker::Diamond, true, {}};
  PlotSeries front{"Pareto front", {210, 40, 40}, 0, true, Marker::Circle, true, {}};
  // Hollow like the other controls; colours and markers apart from every other series.
  static const Rgb kCurveColours[] = {{0, 140, 130}, {150, 70, 170}, {220, 130, 20}};
  static const Marker kCurveMarkers[] = {Marker::Square, Marker::Triangle, Marker::Circle};
  std::vector<PlotSeries> curves;
  std::map<std::string, std::pair<size_t, std::string>> on_curve;  // row name -> (curve, label)
  for (size_t c = 0; c < roles.curves.size(); ++c) {
    curves.push_back({roles.curves[c].name, kCurveColours[c % 3], 5, true, kCurveMarkers[c % 3], false, {}});
    for (const auto& [row, label] : roles.curves[c].points) on_curve[row] = {c, label};
  }
  std::map<std::string, std::pair<double, double>> at;  // row name -> (latency, PSNR)
  ReportTable shown = table;
  if (networks_only)
    shown.rows.erase(std::remove_if(shown.rows.begin(), shown.rows.end(), [](const EvalResult& r) { return !r.cost; }),
                     shown.rows.end());
  const auto on_front = pareto_front(shown);
  for (size_t i = 0; i < shown.rows.size(); ++i) {
    const auto& r = shown.rows[i];
    if (!r.latency) {
      plot.horizontal_lines.emplace_back(r.psnr, r.name + " (no latency)");
      continue;
    }
    const PlotPoint p{r.latency->median_ms, r.psnr, r.name};
    at[r.name] = {p.x, p.y};
    if (const auto curve = on_curve.find(r.name); curve != on_curve.end())
      curves[curve->second.first].points.push_back({p.x, p.y, curve->second.second});
    else
      (named(roles.finals, r.name) ? final_net : named(roles.controls, r.name) ? control : !r.cost ? classic : network)
          .points.push_back(p);
    if (std::find(on_front.begin(), on_front.end(), i) != on_front.end()) front.points.push_back({p.x, p.y, ""});
  }
  for (const auto& [a, b] : roles.pairs)
    if (at.count(a) && at.count(b)) plot.links.push_back({at[a].first, at[a].second, at[b].first, at[b].second});
  plot.links_name = "a network and its control";
  for (auto* s : {&front, &classic, &network, &control})
    if (!s->points.empty()) plot.series.push_back(*s);
  for (const auto& s : curves)
    if (!s.points.empty()) plot.series.push_back(s);
  if (!final_net.points.empty()) plot.series.push_back(final_net);  // drawn last: on top
  return plot;
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

nlohmann::ordered_json write_report(const std::vector<EvalResult>& evaluations, RunDir& run_dir,
                                    const std::vector<std::string>& heldout_scenes, const ReportRoles& roles,
                                    const std::vector<ComparisonImage>& comparisons) {
  const auto tables = group_results(evaluations);
  std::string markdown;
  nlohmann::ordered_json results;
  results["tables"] = nlohmann::ordered_json::array();
  results["pattern_choices"] = nlohmann::ordered_json::array();
  // Each plot as PNG for the Markdown report and as SVG for the page.
  const auto save_canvas = [&](const std::string& stem, const Canvas& canvas) {
    canvas.save(run_dir.file(stem + ".png"));
    canvas.save(run_dir.file(stem + ".svg"));
  };
  const auto save_plot = [&](const std::string& stem, const ScatterPlot& plot) {
    save_canvas(stem, *draw_scatter_plot(plot));
  };
  for (size_t ti = 0; ti < tables.size(); ++ti) {
    const ReportTable& t = tables[ti];
    const std::string stem = table_file_stem(tables, ti);
    const bool heldout = std::find(heldout_scenes.begin(), heldout_scenes.end(), t.dataset) != heldout_scenes.end();
    if (heldout)
      markdown += "## Held-out scene: " + t.dataset +
                  "\n\nNot in the training data: how the networks do on content they never saw (quality only; "
                  "latency is the run's own table's).\n\n";
    markdown += report_markdown(t) + "\n";
    // A plot of PSNR against latency needs a latency (held-out scenes are evaluated for quality only).
    std::string plot, networks_plot;
    const auto timed = [&](bool network) {
      return std::count_if(t.rows.begin(), t.rows.end(), [&](const EvalResult& r) {
        return r.latency.has_value() && r.cost.has_value() == network;
      });
    };
    if (timed(true) + timed(false) > 0) {
      plot = "plot_" + stem;
      save_plot(plot, report_plot(t, roles));
      markdown += "![PSNR against latency](" + plot + ".png)\n\n";
    }
    // The networks again, closer, when the classic upscalers stretch the axes.
    if (timed(false) > 0 && timed(true) > 1) {
      networks_plot = plot + "_networks";
      save_plot(networks_plot, report_plot(t, roles, true));
      markdown += "![PSNR against latency, the networks](" + networks_plot + ".png)\n\n";
    }
    std::string frame_plot;
    if (const auto per_frame = psnr_per_frame_plot(t)) {
      frame_plot = psnr_per_frame_plot_name(stem);
      save_canvas(frame_plot, *draw_line_plot(*per_frame));
      markdown += "![PSNR per frame](" + frame_plot + ".png)\n\n";
    }
    results["tables"].push_back({{"dataset", t.dataset},
                                 {"scale", t.scale},
                                 {"target", t.target},
                                 {"rows", t.rows.size()},
                                 {"plot", plot.empty() ? "" : plot + ".png"},
                                 {"plot_svg", plot.empty() ? "" : plot + ".svg"},
                                 {"networks_plot", networks_plot.empty() ? "" : networks_plot + ".png"},
                                 {"networks_plot_svg", networks_plot.empty() ? "" : networks_plot + ".svg"},
                                 {"frame_plot", frame_plot.empty() ? "" : frame_plot + ".png"},
                                 {"frame_plot_svg", frame_plot.empty() ? "" : frame_plot + ".svg"},
                                 {"heldout", heldout}});
    // Models that choose a pattern per frame: the choice next to each frame's edge density.
    for (size_t i = 0; i < t.rows.size(); ++i) {
      const auto choices = pattern_choices(t.rows[i]);
      if (!choices) continue;
      std::string choice_plot = "pattern_choice_" + stem + "_" + std::to_string(i + 1);
      const bool has_edges = std::any_of(choices->frames.begin(), choices->frames.end(),
                                         [](const FrameChoice& c) { return c.edge_fraction.has_value(); });
      if (has_edges)
        save_plot(choice_plot, pattern_choice_plot(t.rows[i].name, *choices));
      else
        choice_plot.clear();
      markdown += pattern_choice_markdown(t.rows[i].name, *choices, choice_plot.empty() ? "" : choice_plot + ".png");
      results["pattern_choices"].push_back({{"dataset", t.dataset},
                                            {"scale", t.scale},
                                            {"target", t.target},
                                            {"model", t.rows[i].name},
                                            {"patterns_used", choices->usage.size()},
                                            {"plot", choice_plot.empty() ? "" : choice_plot + ".png"},
                                            {"plot_svg", choice_plot.empty() ? "" : choice_plot + ".svg"}});
    }
  }
  if (!comparisons.empty()) {
    markdown += "## Image comparisons\n\nThe same crop of each upscaler's output, where the networks differ most from "
                "bicubic, and each one's absolute error on one colour scale.\n\n";
    for (const auto& c : comparisons)
      markdown += "### " + c.dataset + ", frame " + std::to_string(c.frame) + "\n\n![crops](images/" + c.crops +
                  ")\n\n![error maps](images/" + c.errors + ")\n\n";
  }
  write_file_atomic(run_dir.file("report.md"), markdown);
  write_file_atomic(run_dir.file("report.csv"), report_csv(tables));
  std::printf("%s", markdown.c_str());
  results["comparisons"] = nlohmann::ordered_json::array();
  for (const auto& c : comparisons) results["comparisons"].push_back(to_json(c));
  results["evaluations"] = nlohmann::ordered_json::array();
  for (const auto& e : evaluations) results["evaluations"].push_back(to_json(e));
  write_report_page(run_dir.path(), results);
  return results;
}

}  // namespace cgsr
