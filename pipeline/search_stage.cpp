#include "pipeline/search_stage.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <limits>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/plot.h"
#include "core/yaml_json.h"
#include "eval/relative_latency.h"
#include "models/complexity.h"
#include "models/elastic.h"
#include "models/latency_table.h"
#include "models/model_file.h"
#include "models/subnet.h"
#include "pipeline/eval_stage.h"
#include "render_data/dataset.h"
#include "train/distillation.h"

namespace cgsr {

namespace {
config::Schema<PickOptions> pick_schema() {
  config::Schema<PickOptions> s;
  s.field("latency_fraction", &PickOptions::latency_fraction,
          "latency budget of the pick, as a fraction of the reference's latency (predicted, then measured)")
      .range(0.001, 1);
  s.field("latency_ms", &PickOptions::latency_ms, "latency budget in ms (when > 0; replaces latency_fraction)")
      .at_least(0);
  s.field("reference", &PickOptions::reference,
          "model file the subnets are timed against, whose latency latency_fraction is of (\"\": the full network)");
  s.field("measure_runs", &PickOptions::measure_runs,
          "timed runs per subnet when the pick is checked by measured latency (0: the table's prediction decides)")
      .range(0, 100);
  s.validate([](const PickOptions& o, const config::Cursor& at, const YAML::Node& node) {
    if (!o.reference.empty() && o.measure_runs == 0)
      at.child("reference").fail(node["reference"], "a reference is timed: it needs measure_runs > 0");
  });
  return s;
}

config::Schema<FinalTraining> final_schema() {
  config::Schema<FinalTraining> s;
  s.section("schedule", &FinalTraining::schedule, schedule_schema(), "fine-tuning of the pick");
  s.section("loss", &FinalTraining::loss, loss_schema(), "its loss");
  s.field("distill", &FinalTraining::distill, "weight of the full network's output beside the HR frame's").range(0, 100);
  return s;
}

nlohmann::ordered_json candidate_json(const Candidate& c) {
  return {{"key", c.key}, {"generation", c.generation}, {"quality", c.quality}, {"score", c.score},
          {"subnet", to_json(c.subnet)}};
}

// The pick as measured against the reference, kept in pick.json: timings differ between runs,
// so a search resumed after its pick fine-tunes the subnet it measured, not another.
struct MeasuredChoice {
  MeasuredPick measured;  // its values in the budget's unit: ms, or a fraction of the reference
  std::string reference;  // what the subnets were timed against ("": not timed)
  RelativeLatency full;   // the full network against it
  std::map<std::string, RelativeLatency> timed;  // every subnet timed, by key
  double predicted_budget_ms = 0;                // the budget in the latency table's terms
};

nlohmann::ordered_json to_json(const RelativeLatency& r) { return {{"ms", r.ms}, {"reference_ms", r.reference_ms}}; }
RelativeLatency relative_latency_from(const nlohmann::json& j) {
  return {j.at("ms").get<double>(), j.at("reference_ms").get<double>()};
}

nlohmann::ordered_json to_json(const MeasuredChoice& c) {
  nlohmann::ordered_json j = {{"key", c.measured.pick.key}, {"fits", c.measured.fits}, {"reference", c.reference},
                              {"predicted_budget_ms", c.predicted_budget_ms}, {"full", to_json(c.full)},
                              {"timed", nlohmann::ordered_json::array()}};
  for (const auto& [key, value] : c.measured.timed) {
    nlohmann::ordered_json t = to_json(c.timed.at(key));
    t["key"] = key;
    j["timed"].push_back(t);
  }
  return j;
}

// The pick by the table's prediction alone.
MeasuredChoice predicted_choice(const Candidate& full, const std::vector<Candidate>& front, const PickOptions& options) {
  MeasuredChoice c;
  c.predicted_budget_ms = options.latency_ms > 0 ? options.latency_ms : options.latency_fraction * full.score.latency_ms;
  c.measured.pick = pick_within(front, c.predicted_budget_ms);
  return c;
}

// The pick by measured latency: the full network and the front's subnets timed against the
// reference; the table's budget is the measured one scaled by the full network's prediction error.
MeasuredChoice measured_choice(const SRNetwork& net, const Candidate& full, const std::vector<Candidate>& front,
                               const Dataset& data, const SearchCommandOptions& options,
                               const std::filesystem::path& file) {
  const bool absolute = options.pick.latency_ms > 0;
  const double budget = absolute ? options.pick.latency_ms : options.pick.latency_fraction;
  const auto value = [&](const RelativeLatency& r) { return absolute ? r.ms : r.fraction(); };
  MeasuredChoice c;
  if (options.resume && std::filesystem::exists(file)) {
    const auto j = nlohmann::json::parse(read_file(file));
    if (!j.contains("reference"))
      throw Error(file.string(), "was written by an older cgsr (no reference); delete it to time the front again");
    const auto key = j.at("key").get<std::string>();
    const auto it = std::find_if(front.begin(), front.end(), [&](const Candidate& f) { return f.key == key; });
    if (it == front.end()) throw Error(file.string(), "names subnet " + key + ", which is not on the search's front");
    c.measured.pick = *it;
    c.measured.fits = j.at("fits").get<bool>();
    c.reference = j.at("reference").get<std::string>();
    c.predicted_budget_ms = j.at("predicted_budget_ms").get<double>();
    c.full = relative_latency_from(j.at("full"));
    for (const auto& t : j.at("timed")) {
      const auto timed_key = t.at("key").get<std::string>();
      c.timed[timed_key] = relative_latency_from(t);
      c.measured.timed.emplace_back(timed_key, value(c.timed[timed_key]));
    }
    c.measured.measured = value(c.timed.at(key));
    spdlog::info("search: the pick measured before, from {}", file.string());
    return c;
  }
  std::unique_ptr<Upscaler> reference =
      options.pick.reference.empty() ? std::make_unique<NetworkUpscaler>("the full network", net)
                                     : make_upscaler(options.pick.reference, "", net->spec().scale);
  c.reference = reference->name();
  const LatencyReference timer(std::move(reference), data, data.frames(Split::Val), options.pick.measure_runs);
  const auto time = [&](const Candidate& sub) {
    NetworkUpscaler upscaler(sub.key, materialize_subnet(*net, sub.subnet, /*geometry_head=*/false));
    return c.timed[sub.key] = timer.time(upscaler);
  };
  c.full = time(full);
  c.predicted_budget_ms = full.score.latency_ms * budget / value(c.full);
  c.measured = pick_measured(front, c.predicted_budget_ms, budget, [&](const Candidate& f) { return value(time(f)); });
  const RelativeLatency& pick = c.timed.at(c.measured.pick.key);
  spdlog::info("search: {} subnets timed against {} (the full network: {:.1f} against {:.1f} ms); the best within "
               "{:g}{} measures {:.1f} against {:.1f} ms ({:.1f}%){}",
               c.measured.timed.size(), c.reference, c.full.ms, c.full.reference_ms, budget,
               absolute ? " ms" : " of it", pick.ms, pick.reference_ms, 100 * pick.fraction(),
               c.measured.fits ? "" : " (none fits: the fastest)");
  write_file_atomic(file, to_json(c).dump(2) + "\n");
  return c;
}

struct SearchRun {
  std::string strategy;
  SearchResult result;
  double hypervolume = 0;
};

void write_front_plot(const std::filesystem::path& path, const std::vector<SearchRun>& runs, const Candidate& full,
                      const Candidate& pick, double budget_ms) {
  ScatterPlot plot;
  plot.title = "search: validation quality against predicted latency";
  plot.x_label = "predicted latency (ms)";
  plot.y_label = "validation PSNR (dB)";
  const std::vector<Rgb> dots = {{120, 160, 230}, {190, 190, 190}}, lines = {{30, 70, 170}, {110, 110, 110}};
  for (size_t r = 0; r < runs.size(); ++r) {
    PlotSeries all{runs[r].strategy + " (" + std::to_string(runs[r].result.evaluated.size()) + " subnets)", dots[r % 2],
                   2, false, Marker::Circle, true, {}};
    for (const auto& c : runs[r].result.evaluated)
      if (!c.failed) all.points.push_back({c.score.latency_ms, c.quality, ""});
    PlotSeries front{runs[r].strategy + " front", lines[r % 2], 4, true, Marker::Circle, true, {}};
    for (const auto& c : runs[r].result.front) front.points.push_back({c.score.latency_ms, c.quality, ""});
    plot.series.push_back(all);
    plot.series.push_back(front);
  }
  plot.series.push_back(
      {"full network", {20, 20, 20}, 6, false, Marker::Square, true, {{full.score.latency_ms, full.quality, "full"}}});
  plot.series.push_back(
      {"pick", {220, 40, 40}, 7, false, Marker::Diamond, true, {{pick.score.latency_ms, pick.quality, "pick"}}});
  plot.notes.push_back("latency budget " + fmt::format("{:.1f}", budget_ms) + " ms");
  write_scatter_plot(path, plot);
}
}  // namespace

config::Schema<SearchCommandOptions> search_command_schema() {
  config::Schema<SearchCommandOptions> s;
  s.field("model", &SearchCommandOptions::model, "elastic model file (cgsr train with elastic.enabled)").required();
  s.field("data", &SearchCommandOptions::data, "data set directory").required();
  s.inline_section(&SearchCommandOptions::search, search_schema());
  s.field("baseline", &SearchCommandOptions::baseline,
          "a strategy run with as many evaluations, the search's control (\"\": none)");
  s.section("crops", &SearchCommandOptions::crops, validation_crop_schema(), "the validation crops subnets are scored on");
  s.section("pick", &SearchCommandOptions::pick, pick_schema(), "which subnet of the front becomes the network");
  s.section("final", &SearchCommandOptions::final, final_schema(), "fine-tuning of the pick, distilled from the full network");
  s.field("name", &SearchCommandOptions::name, "display name of the result in reports");
  s.field("resume", &SearchCommandOptions::resume, "continue from the histories and the final checkpoint");
  s.validate([](const SearchCommandOptions& o, const config::Cursor& at, const YAML::Node& node) {
    if (!o.baseline.empty() && !strategy_registry().contains(o.baseline))
      at.child("baseline").fail(node["baseline"], "unknown search strategy '" + o.baseline + "'; valid: " +
                                                      join(strategy_registry().names()));
  });
  add_run_settings(s);
  return s;
}

nlohmann::ordered_json run_search_command(const SearchCommandOptions& options, const YAML::Node& resolved,
                                          RunDir& run_dir) {
  Model elastic = load_model(options.model);
  const ElasticSpace space = elastic_space_from(elastic.network->spec(), elastic.provenance.extra, options.model);
  const std::map<Precision, LatencyTable> tables = latency_tables_from(elastic.provenance.extra, options.model);
  for (Precision p : space.options().precisions)
    if (!tables.count(p))
      throw Error(options.model, "has no " + enum_name(p) + " latency table (train it with elastic.enabled" +
                                     (p == Precision::Fp32 ? ")" : " and elastic.space.precisions listing it)"));
  const LatencyTable& table = tables.at(Precision::Fp32);
  std::vector<RenderChannel> channels = elastic.network->input_channels();
  channels.push_back(RenderChannel::Edge);
  const Dataset data = open_for_channels(options.data, channels);
  InferenceEvaluator evaluator(elastic.network, data, options.crops, tables);
  std::vector<std::string> precisions;
  for (Precision p : space.options().precisions) precisions.push_back(enum_name(p));
  spdlog::info("search: {} elastic layer groups, {} blocks (at least {}), precisions {}; scoring on {} validation "
               "crops; latency tables at {}x{}",
               space.genes().size(), space.total_blocks(), space.min_blocks(), join(precisions),
               evaluator.crops(), table.lr_width, table.lr_height);
  for (const auto& [p, t] : tables)
    spdlog::info("search: {} latency table: prediction error {:.1f}% mean, {:.1f}% max", enum_name(p),
                 t.error.mean_abs_percent, t.error.max_abs_percent);

  Candidate full;
  full.subnet = space.full();
  full.key = subnet_key(full.subnet);
  full.score = evaluator.evaluate(full.subnet);
  full.quality = candidate_quality(full.score, options.search.edge_weight);

  std::vector<SearchRun> runs;
  std::vector<std::pair<std::string, std::string>> plan = {{options.search.strategy.type, "history.jsonl"}};
  if (!options.baseline.empty()) plan.emplace_back(options.baseline, options.baseline + "_history.jsonl");
  for (const auto& [strategy, file] : plan) {
    SearchOptions o = options.search;
    if (strategy != o.strategy.type) o.strategy = StrategyOptions{strategy, {}};
    SearchHistory history(run_dir.file(file), options.resume);
    runs.push_back({strategy, run_search(space, evaluator, history, o, strategy), 0});
  }
  // One reference for every front: the full network's latency, the worst quality any run saw.
  double quality_ref = full.quality;
  for (const auto& r : runs)
    for (const auto& c : r.result.evaluated)
      if (!c.failed) quality_ref = std::min(quality_ref, c.quality);
  const double latency_ref = full.score.latency_ms;
  for (auto& r : runs) r.hypervolume = front_hypervolume(r.result.front, latency_ref, quality_ref);

  const std::vector<Candidate>& front = runs.front().result.front;
  const MeasuredChoice choice =
      options.pick.measure_runs > 0
          ? measured_choice(elastic.network, full, front, data, options, run_dir.file("pick.json"))
          : predicted_choice(full, front, options.pick);
  const double budget = choice.predicted_budget_ms;
  const Candidate& pick = choice.measured.pick;
  write_front_plot(run_dir.file("front.png"), runs, full, pick, budget);
  spdlog::info("search: pick {} at {:.1f} ms predicted ({:.0f}% of the full network's {:.1f} ms), {:.3f} dB "
               "(full: {:.3f} dB)", pick.key, pick.score.latency_ms, 100.0 * pick.score.latency_ms / latency_ref,
               latency_ref, pick.quality, full.quality);

  // The CG-optimized network: the pick as a network of its own, fine-tuned from the full one.
  SRNetwork picked = materialize_subnet(*elastic.network, pick.subnet);
  const std::string name = options.name.empty() ? "CG-optimized " + spec_summary(picked->spec()) : options.name;
  Provenance provenance;
  provenance.stage = "search";
  provenance.parent = options.model;
  provenance.config = yaml_to_json(resolved);
  provenance.extra = {{"name", name}, {"data", data.info().root.string()}, {"subnet", to_json(pick.subnet)}};
  save_model(run_dir.file("subnet.cgsr"), *picked, provenance);
  save_spec_file(run_dir.file("pick_spec.yaml"), picked->spec());  // what the scratch control trains
  TrainHooks hooks;
  if (options.final.distill > 0)
    hooks = distillation_hooks(elastic.network, options.final.distill, options.final.loss.image_norm);
  Trainer trainer(picked, data, options.final.schedule, options.final.loss, {}, hooks);
  const TrainOutcome final_training = trainer.run(run_dir.file("final_checkpoint.pt"), options.resume);
  provenance.metrics = {{"val_psnr", final_training.best.psnr}, {"val_ssim", final_training.best.ssim}};
  save_model(run_dir.file("model.cgsr"), *picked, provenance);

  nlohmann::ordered_json j;
  j["name"] = name;
  j["model"] = run_dir.file("model.cgsr").string();
  j["subnet_model"] = run_dir.file("subnet.cgsr").string();
  j["elastic"] = options.model;
  for (const auto& [p, t] : tables)
    j[latency_table_key(p)] = {{"lr_size", {t.lr_width, t.lr_height}},
                               {"convolution_shapes", t.conv_ms.size()},
                               {"prediction_error", {{"subnets", t.error.subnets},
                                                     {"mean_abs_percent", t.error.mean_abs_percent},
                                                     {"max_abs_percent", t.error.max_abs_percent}}}};
  j["crops"] = evaluator.crops();
  j["full"] = candidate_json(full);
  j["hypervolume_reference"] = {{"latency_ms", latency_ref}, {"quality", quality_ref}};
  for (const auto& r : runs) {
    nlohmann::ordered_json s;
    s["evaluations"] = r.result.evaluated.size();
    s["generations"] = r.result.generations_run;
    s["failures"] = r.result.failures;
    s["stop_reason"] = r.result.stop_reason;
    s["hypervolume"] = r.hypervolume;
    s["front"] = nlohmann::ordered_json::array();
    for (const auto& c : r.result.front) s["front"].push_back(candidate_json(c));
    j["searches"][r.strategy] = s;
    spdlog::info("search: {}: {} subnets, front of {}, hypervolume {:.2f} dB ms", r.strategy, r.result.evaluated.size(),
                 r.result.front.size(), r.hypervolume);
  }
  j["pick"] = candidate_json(pick);
  j["pick"]["budget_ms"] = budget;
  if (options.pick.measure_runs > 0) j["pick"]["measured"] = to_json(choice);
  j["pick"]["spec"] = spec_summary(picked->spec());
  j["pick"]["params"] = inference_parameter_count(*picked);
  j["final_training"] = to_json(final_training);
  return j;
}

}  // namespace cgsr
