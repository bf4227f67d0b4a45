#include "cli/commands/search.h"

#include <spdlog/spdlog.h>

#include "core/plot.h"
#include "core/yaml_json.h"
#include "models/inherit.h"
#include "models/model_file.h"
#include "render_data/dataset.h"

namespace cgsr::cli {

config::Schema<SearchCommandOptions> search_command_schema() {
  config::Schema<SearchCommandOptions> s;
  s.field("parent", &SearchCommandOptions::parent, "CG-enhanced model file to start from").required();
  s.field("data", &SearchCommandOptions::data, "data set directory").required();
  s.inline_section(&SearchCommandOptions::search, search_schema());
  s.moved_block("search");  // configs before the search options moved up: `search: {strategy: ...}`
  s.upgrade(move_operators_into_strategy);  // lifted from `search:` or at the top
  s.section("candidate", &SearchCommandOptions::candidate, candidate_training_schema(), "training of each candidate");
  s.section("final", &SearchCommandOptions::final_schedule, schedule_schema(), "training of the picked network");
  s.field("name", &SearchCommandOptions::name, "display name of the result in reports");
  s.field("resume", &SearchCommandOptions::resume, "continue from history.jsonl and the final checkpoint");
  add_run_settings(s);
  return s;
}

void setup_search(CLI::App& app) {
  add_command<SearchCommandOptions>(
      app, "search", "CG-guided evolutionary architecture search (CG-enhanced -> CG-optimized)",
      search_command_schema,
      [](CLI::App& sub, std::vector<FlagAssignment>& flags) {
        flag_to_key(sub, flags, "--parent", "parent", "CG-enhanced model file");
        flag_to_key(sub, flags, "--data", "data", "data set directory");
        flag_to_key(sub, flags, "--strategy", "strategy", "evolution or random (with its default options)");
        switch_to_key(sub, flags, "--resume", "resume", "continue an interrupted search in --out");
      },
      [](const SearchCommandOptions& options, const YAML::Node& resolved, RunDir* run_dir) {
        return run_search_command(options, resolved, *run_dir);
      },
      /*always_run_dir=*/true);
}

YAML::Node search_config_cache_form(const YAML::Node& resolved) {
  const auto search_keys = search_schema().keys();
  const auto is_search_key = [&](const std::string& key) {
    return std::find(search_keys.begin(), search_keys.end(), key) != search_keys.end();
  };
  // The search block as it was: the strategy's name, and evolution's options in `operators:`
  // after `space:` (for every strategy: the random one ignored them).
  YAML::Node search(YAML::NodeType::Map);
  for (const auto& kv : resolved) {
    const std::string key = kv.first.Scalar();
    if (!is_search_key(key)) continue;
    if (key == "strategy") {
      search[key] = kv.second["type"];
      continue;
    }
    search[key] = kv.second;
    if (key != "space") continue;
    YAML::Node operators = evolution_schema().emit(EvolutionOptions{});
    if (resolved["strategy"]["type"].Scalar() == "evolution")
      for (const auto& option : resolved["strategy"])
        if (option.first.Scalar() != "type") operators[option.first.Scalar()] = option.second;
    search["operators"] = operators;
  }
  YAML::Node out(YAML::NodeType::Map);
  bool placed = false;
  for (const auto& kv : resolved) {
    const std::string key = kv.first.Scalar();
    if (!is_search_key(key)) {
      out[key] = kv.second;
    } else if (!placed) {
      out["search"] = search;  // the block sat where its first key sits now
      placed = true;
    }
  }
  return out;
}

namespace {
void write_population_plot(const std::filesystem::path& path, const SearchResult& result) {
  ScatterPlot plot;
  plot.title = "search: validation PSNR against parameters";
  plot.x_label = "parameters (k)";
  plot.y_label = "validation PSNR (dB)";
  PlotSeries candidates{"candidate", {90, 140, 220}, 4, false, {}};
  for (const auto& c : result.evaluated) candidates.points.push_back({c.score.params / 1000.0, c.score.val_psnr, ""});
  PlotSeries parent{"CG-enhanced parent", {30, 30, 30}, 7, false,
                    {{result.parent.score.params / 1000.0, result.parent.score.val_psnr, "parent"}}};
  PlotSeries pick{"pick (smallest within tolerance)", {220, 40, 40}, 7, false,
                  {{result.pick.score.params / 1000.0, result.pick.score.val_psnr, "pick"}}};
  plot.series = {candidates, parent, pick};
  write_scatter_plot(path, plot);
}
}  // namespace

nlohmann::ordered_json run_search_command(const SearchCommandOptions& options, const YAML::Node& resolved,
                                          RunDir& run_dir) {
  const Dataset data = Dataset::open(options.data);
  Model parent = load_model(options.parent);
  if (!parent.network->has_rit())
    spdlog::warn("{}: the parent has no RIT block; the search runs on the plain backbone", options.parent);

  SearchHistory history(run_dir.file("history.jsonl"), options.resume);
  TrainingEvaluator evaluator(parent.network, data, options.candidate);
  const SearchResult result = run_search(parent.network->spec(), evaluator, history, options.search);
  write_population_plot(run_dir.file("population.png"), result);
  if (result.pick_is_parent)
    spdlog::warn("no candidate stayed within {} dB of the parent; the parent is kept", options.search.tolerance_db);

  // The CG-optimized network: the pick, inherited from the parent and trained longer.
  SRNetwork picked = inherit(*parent.network, result.pick.spec).network;
  Trainer trainer(picked, data, options.final_schedule, options.candidate.loss);
  const TrainOutcome final_training = trainer.run(run_dir.file("final_checkpoint.pt"), options.resume);

  const std::string name = options.name.empty() ? "CG-optimized " + spec_summary(picked->spec()) : options.name;
  Provenance provenance;
  provenance.stage = "search";
  provenance.parent = options.parent;
  provenance.config = yaml_to_json(resolved);
  provenance.metrics = {{"val_psnr", final_training.best.psnr}, {"val_ssim", final_training.best.ssim}};
  provenance.extra = {{"name", name}, {"data", data.info().root.string()}};
  save_model(run_dir.file("model.cgsr"), *picked, provenance);

  const double reduction = 1.0 - static_cast<double>(result.pick.score.params) / result.parent.score.params;
  spdlog::info("search: {} -> {} params ({:.1f}% fewer; paper, Fig. 6(b): 37%), {} candidates in {} generations ({})",
               result.parent.score.params, result.pick.score.params, 100.0 * reduction, result.evaluated.size(),
               result.generations_run, result.stop_reason);

  nlohmann::ordered_json j;
  j["name"] = name;
  j["model"] = run_dir.file("model.cgsr").string();
  j["parent"] = {{"spec", spec_summary(result.parent.spec)}, {"score", to_json(result.parent.score)}};
  j["pick"] = {{"spec", spec_summary(result.pick.spec)},
               {"spec_yaml", spec_to_yaml(result.pick.spec)},
               {"score", to_json(result.pick.score)},
               {"is_parent", result.pick_is_parent}};
  j["param_reduction"] = reduction;
  j["pareto_front"] = nlohmann::ordered_json::array();
  for (const auto& c : pareto_front(result.evaluated))
    j["pareto_front"].push_back({{"spec", spec_summary(c.spec)}, {"params", c.score.params}, {"val_psnr", c.score.val_psnr}});
  j["candidates"] = result.evaluated.size();
  j["generations"] = result.generations_run;
  j["stop_reason"] = result.stop_reason;
  j["final_training"] = to_json(final_training);
  return j;
}

}  // namespace cgsr::cli
