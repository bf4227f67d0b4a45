#include "pipeline/ablation.h"

#include <spdlog/spdlog.h>
#include <torch/torch.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/plot.h"
#include "core/runtime.h"
#include "core/text.h"
#include "eval/upscaler.h"
#include "models/complexity.h"
#include "models/inherit.h"
#include "models/model_file.h"

namespace cgsr {

config::Schema<AblationOptions> ablation_schema_fields() {
  config::Schema<AblationOptions> s;
  s.field("sources", &AblationOptions::sources, "RIT sources to compare (rit.h)");
  s.section("rit", &AblationOptions::rit, rit_spec_schema(), "the RIT of every CG-enhanced variant");
  s.field("leave_out", &AblationOptions::leave_out, "the best source with each rendering channel left out in turn");
  s.field("channel_sets", &AblationOptions::channel_sets,
          "channel lists to try at the best source besides rit.channels (render_channels.h names)")
      .check(
          [](const std::vector<std::vector<std::string>>& sets) {
            for (const auto& set : sets) {
              if (set.empty()) return false;
              try {
                parse_channels(set);
              } catch (const Error&) {
                return false;
              }
            }
            return true;
          },
          "every set needs at least one channel, each a render channel name (" +
              join(channel_names(all_render_channels())) + ") at most once");
  s.field("small_width", &AblationOptions::small_width, "width factor of the small networks (0 = none)").range(0, 1);
  s.field("seeds", &AblationOptions::seeds, "seeds; every variant trains once per seed")
      .check([](const std::vector<int64_t>& v) { return !v.empty(); }, "needs at least one seed");
  s.section("schedule", &AblationOptions::schedule, schedule_schema(), "the schedule of every variant");
  s.section("loss", &AblationOptions::loss, loss_schema(), "loss weights of every variant");
  s.section("eval", &AblationOptions::eval, eval_schema_fields(), "evaluation of every variant");
  return s;
}

namespace {

std::string slug(const std::string& name) {
  std::string out;
  for (char c : name) {
    if (std::isalnum(static_cast<unsigned char>(c)))
      out += c;
    else if (!out.empty() && out.back() != '_')
      out += '_';
  }
  while (!out.empty() && out.back() == '_') out.pop_back();
  return out;
}

ArchSpec with_source(ArchSpec spec, const RitSpec& rit, RitSource source) {
  spec.rit = rit;
  spec.rit.enabled = true;
  spec.rit.source = source;
  spec.geometry.enabled = false;
  return resolve_spec(spec);
}

// Every backbone width times `factor` (at least 1): about factor^2 of the parameters.
ArchSpec shrunk(ArchSpec spec, double factor) {
  GroupWidths widths;
  for (const auto& [group, width] : spec.widths.entries())
    widths.set(group, std::max(1, static_cast<int>(std::lround(width * factor))));
  spec.widths = widths;
  return resolve_spec(spec);
}

double mean(const std::vector<double>& v) {
  if (v.empty()) return std::nan("");
  double s = 0;
  for (double x : v) s += x;
  return s / static_cast<double>(v.size());
}

nlohmann::ordered_json run_to_json(const AblationRun& r) {
  return {{"variant", r.variant}, {"seed", r.seed},   {"val_psnr", r.val_psnr},
          {"params", r.params},   {"macs", r.macs},   {"eval", to_json(r.eval)}};
}

AblationRun run_from_json(const nlohmann::ordered_json& j, const std::string& context) {
  AblationRun r;
  r.variant = j.at("variant").get<std::string>();
  r.seed = j.at("seed").get<int64_t>();
  r.val_psnr = j.at("val_psnr").get<double>();
  r.params = j.at("params").get<int64_t>();
  r.macs = j.at("macs").get<int64_t>();
  r.eval = eval_result_from_json(j.at("eval"), context);
  return r;
}

class Runner {
 public:
  Runner(const SRNetworkImpl& parent, const Dataset& data, const AblationOptions& options,
         const std::filesystem::path& dir)
      : parent_(parent), data_(data), options_(options), dir_(dir) {}

  AblationRow run(const AblationVariant& v) {
    AblationRow row;
    row.variant = v;
    for (int64_t seed : options_.seeds) {
      const AblationRun r = run_once(v, seed);
      row.params = r.params;
      row.macs = r.macs;
      row.seeds.push_back(seed);
      row.psnr.push_back(r.eval.psnr);
      row.val_psnr.push_back(r.val_psnr);
      if (r.eval.psnr_edge) row.psnr_edge.push_back(*r.eval.psnr_edge);
      if (r.eval.psnr_rest) row.psnr_rest.push_back(*r.eval.psnr_rest);
    }
    spdlog::info("ablation: {}: test {:.3f} dB (edges {:.3f} dB) over {} seed(s)", v.name, mean(row.psnr),
                 mean(row.psnr_edge), row.psnr.size());
    return row;
  }

 private:
  AblationRun run_once(const AblationVariant& v, int64_t seed) {
    const auto dir = dir_ / "variants" / slug(v.name) / ("seed" + std::to_string(seed));
    const auto record = dir / "run.json";
    // A run trained under other settings (an edited config) is not resumed or reused.
    const auto stamp = dir / "settings.yaml";
    const std::string settings = run_settings(v, seed);
    if (std::filesystem::exists(stamp) && read_file(stamp) != settings) {
      spdlog::warn("ablation: {} seed {} was trained under other settings; training it again", v.name, seed);
      std::filesystem::remove_all(dir);
    }
    std::filesystem::create_directories(dir);
    write_file_atomic(stamp, settings);
    if (std::filesystem::exists(record)) {
      const auto j = nlohmann::ordered_json::parse(read_file(record));
      spdlog::info("ablation: {} seed {} already done", v.name, seed);
      return run_from_json(j, record.string());
    }
    spdlog::info("ablation: training {} ({}), seed {}", v.name, spec_summary(v.spec), seed);
    seed_everything(static_cast<uint64_t>(seed));  // the fresh RIT and the batches depend on the seed only
    SRNetwork net = inherit(parent_, v.spec).network;
    Trainer trainer(net, data_, options_.schedule, options_.loss);
    const TrainOutcome outcome = trainer.run(dir / "checkpoint.pt", /*resume=*/true);
    net->eval();
    Provenance provenance;
    provenance.stage = "ablation";
    provenance.metrics = {{"val_psnr", outcome.best.psnr}};
    provenance.extra = {{"name", v.name}, {"seed", seed}};
    save_model(dir / "model.cgsr", *net, provenance);

    AblationRun r;
    r.variant = v.name;
    r.seed = seed;
    r.val_psnr = outcome.best.psnr;
    NetworkUpscaler upscaler(v.name, net);
    r.eval = evaluate(upscaler, data_, options_.eval);
    const Complexity cost = complexity(*net, r.eval.lr_width, r.eval.lr_height);
    r.params = cost.params;
    r.macs = cost.macs;
    write_file_atomic(record, run_to_json(r).dump(2) + "\n");
    std::filesystem::remove(dir / "checkpoint.pt");  // the run is recorded; the model file stays
    return r;
  }

  // Everything a (variant, seed) run's result depends on besides the parent and the data.
  std::string run_settings(const AblationVariant& v, int64_t seed) const {
    YAML::Node node;
    node["spec"] = YAML::Load(spec_to_yaml(v.spec));
    node["seed"] = seed;
    node["schedule"] = schedule_schema().emit(options_.schedule);
    node["loss"] = loss_schema().emit(options_.loss);
    node["eval"] = eval_schema_fields().emit(options_.eval);
    YAML::Emitter out;
    out << node;
    return std::string(out.c_str()) + "\n";
  }

  const SRNetworkImpl& parent_;
  const Dataset& data_;
  const AblationOptions& options_;
  std::filesystem::path dir_;
};

}  // namespace

AblationResult run_ablation(const SRNetworkImpl& parent, const Dataset& data, const AblationOptions& options,
                            const std::filesystem::path& dir) {
  if (parent.has_rit()) throw Error("ablation", "starts from a plain network; the model has a RIT block");
  const ArchSpec plain = [&] {
    ArchSpec s = parent.spec();
    s.geometry.enabled = false;
    return resolve_spec(s);
  }();
  Runner runner(parent, data, options, dir);
  AblationResult result;
  result.rows.push_back(runner.run({"plain (control)", "control", plain}));

  double best_val = -1e300;
  RitSource best = RitSource::Lr;
  for (const auto source : options.sources) {
    result.rows.push_back(runner.run({enum_name(source), "source", with_source(plain, options.rit, source)}));
    const double val = mean(result.rows.back().val_psnr);
    if (val > best_val) {
      best_val = val;
      best = source;
      result.best_source = enum_name(source);
    }
  }
  if (!result.best_source.empty() && options.leave_out && options.rit.channels.size() > 1)
    for (const auto& channel : options.rit.channels) {
      RitSpec rit = options.rit;
      rit.channels.erase(std::find(rit.channels.begin(), rit.channels.end(), channel));
      result.rows.push_back(runner.run({result.best_source + " - " + channel, "leave_out", with_source(plain, rit, best)}));
    }
  if (!result.best_source.empty())
    for (const auto& channels : options.channel_sets) {
      RitSpec rit = options.rit;
      rit.channels = channels;
      const ArchSpec spec = with_source(plain, rit, best);
      const std::string name = result.best_source + " [" + join(spec.rit.channels, "+") + "]";
      result.rows.push_back(runner.run({name, "channels", spec}));
    }
  if (options.small_width > 0) {
    const ArchSpec small = shrunk(plain, options.small_width);
    result.rows.push_back(runner.run({"small plain", "small", small}));
    if (!result.best_source.empty())
      result.rows.push_back(runner.run({"small + " + result.best_source, "small", with_source(small, options.rit, best)}));
  }
  return result;
}

namespace {

std::string signed_fixed(double v, int digits) { return (std::isfinite(v) && v >= 0 ? "+" : "") + fixed(v, digits); }

// "25.412 (25.398..25.426)": the mean and the range over seeds.
std::string mean_range(const std::vector<double>& v) {
  if (v.empty()) return "NA";
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  if (v.size() == 1) return fixed(v.front(), 3);
  return fixed(mean(v), 3) + " (" + fixed(*lo, 3) + ".." + fixed(*hi, 3) + ")";
}

// Per-seed differences to the control (same seed), then their mean.
std::vector<double> gains(const std::vector<double>& v, const std::vector<double>& control) {
  std::vector<double> out;
  for (size_t i = 0; i < v.size() && i < control.size(); ++i) out.push_back(v[i] - control[i]);
  return out;
}

}  // namespace

std::string ablation_markdown(const AblationResult& result) {
  if (result.rows.empty()) return "";
  const auto& control = result.rows.front();
  std::ostringstream md;
  md << "| Variant | Params (k) | MACs (G) | PSNR (dB) | Edge PSNR (dB) | Rest PSNR (dB) | Gain (dB) | Edge gain (dB) |\n"
     << "|---|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const auto& row : result.rows) {
    const auto gain = gains(row.psnr, control.psnr), edge_gain = gains(row.psnr_edge, control.psnr_edge);
    md << "| " << row.variant.name << (row.variant.name == result.best_source ? " **(best)**" : "") << " | "
       << fixed(row.params / 1e3, 1) << " | " << fixed(row.macs / 1e9, 2) << " | " << mean_range(row.psnr) << " | "
       << mean_range(row.psnr_edge) << " | " << mean_range(row.psnr_rest) << " | "
       << (&row == &control ? "" : signed_fixed(mean(gain), 3)) << " | "
       << (&row == &control ? "" : signed_fixed(mean(edge_gain), 3)) << " |\n";
  }
  md << "\nMeans over " << control.psnr.size() << " seed(s), range in brackets; gains are per-seed differences to "
     << "the control (same seed), averaged. Edge PSNR: pixels of the HR geometry-edge map dilated by 1 pixel. "
     << "Best source by validation PSNR: " << (result.best_source.empty() ? "none" : result.best_source) << ".\n";
  // How much of the gap between the small and the full plain network the information closes.
  const AblationRow* small = nullptr;
  const AblationRow* small_cg = nullptr;
  for (const auto& row : result.rows) {
    if (row.variant.name == "small plain") small = &row;
    if (row.variant.name == "small + " + result.best_source) small_cg = &row;
  }
  if (small && small_cg) {
    const double gap = mean(control.psnr) - mean(small->psnr), closed = mean(small_cg->psnr) - mean(small->psnr);
    md << "Small network (" << fixed(100.0 * small->params / std::max<int64_t>(control.params, 1), 0)
       << "% of the parameters): " << fixed(gap, 3) << " dB below the full plain network; the "
       << result.best_source << " information closes " << signed_fixed(closed, 3) << " dB of it ("
       << (gap > 0 ? fixed(100 * closed / gap, 0) + "%" : std::string("no gap")) << ").\n";
  }
  return md.str();
}

std::string ablation_csv(const AblationResult& result) {
  std::ostringstream csv;
  csv << "variant,kind,seed,params,macs,val_psnr,psnr,psnr_edge,psnr_rest\n";
  for (const auto& row : result.rows)
    for (size_t i = 0; i < row.psnr.size(); ++i)
      csv << row.variant.name << "," << row.variant.kind << "," << row.seeds.at(i) << "," << row.params << "," << row.macs << ","
          << fixed(row.val_psnr[i], 4) << "," << fixed(row.psnr[i], 4) << ","
          << (i < row.psnr_edge.size() ? fixed(row.psnr_edge[i], 4) : "") << ","
          << (i < row.psnr_rest.size() ? fixed(row.psnr_rest[i], 4) : "") << "\n";
  return csv.str();
}

void write_ablation_chart(const std::filesystem::path& path, const AblationResult& result) {
  if (result.rows.size() < 2) throw Error(path.string(), "an ablation chart needs variants besides the control");
  const auto& control = result.rows.front();
  BarChart chart;
  chart.title = "Gain over the plain network trained as long (test PSNR)";
  chart.y_label = "dB";
  BarSeries overall{"overall", {40, 90, 180}, {}, {}, {}}, edges{"geometry edges", {220, 110, 30}, {}, {}, {}};
  for (size_t i = 1; i < result.rows.size(); ++i) {
    const auto& row = result.rows[i];
    chart.categories.push_back(row.variant.name);
    for (auto [series, values, base] : {std::make_tuple(&overall, &row.psnr, &control.psnr),
                                        std::make_tuple(&edges, &row.psnr_edge, &control.psnr_edge)}) {
      const auto g = gains(*values, *base);
      series->values.push_back(mean(g));
      series->low.push_back(g.empty() ? std::nan("") : *std::min_element(g.begin(), g.end()));
      series->high.push_back(g.empty() ? std::nan("") : *std::max_element(g.begin(), g.end()));
    }
  }
  chart.series = {overall, edges};
  write_bar_chart(path, chart);
}

nlohmann::ordered_json to_json(const AblationResult& result) {
  nlohmann::ordered_json j;
  j["best_source"] = result.best_source;
  j["rows"] = nlohmann::ordered_json::array();
  for (const auto& row : result.rows)
    j["rows"].push_back({{"variant", row.variant.name},
                         {"kind", row.variant.kind},
                         {"spec", spec_summary(row.variant.spec)},
                         {"params", row.params},
                         {"macs", row.macs},
                         {"seeds", row.seeds},
                         {"val_psnr", row.val_psnr},
                         {"psnr", row.psnr},
                         {"psnr_edge", row.psnr_edge},
                         {"psnr_rest", row.psnr_rest}});
  return j;
}

}  // namespace cgsr
