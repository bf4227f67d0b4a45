#include "pipeline/search_stage.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "core/atomic_file.h"
#include "core/hash.h"
#include "core/plot.h"
#include "core/yaml_json.h"
#include "models/importance/block_importance.h"
#include "models/inherit.h"
#include "models/model_file.h"
#include "pipeline/distributed_run.h"
#include "pipeline/distributed_search.h"
#include "render_data/dataset.h"

namespace cgsr {

config::Schema<SearchCommandOptions> search_command_schema() {
  config::Schema<SearchCommandOptions> s;
  s.field("parent", &SearchCommandOptions::parent, "CG-enhanced model file to start from").required();
  s.field("data", &SearchCommandOptions::data, "data set directory").required();
  s.inline_section(&SearchCommandOptions::search, search_schema());
  // Configs before the search options moved up: `search: {strategy: ...}`; the inlined options'
  // upgrade (a former `operators:` block) then reads it whether lifted from there or at the top.
  s.moved_block("search");
  s.section("candidate", &SearchCommandOptions::candidate, candidate_training_schema(), "training of each candidate");
  s.section("final", &SearchCommandOptions::final_schedule, schedule_schema(), "training of the picked network");
  s.field("name", &SearchCommandOptions::name, "display name of the result in reports");
  s.field("resume", &SearchCommandOptions::resume, "continue from history.jsonl and the final checkpoint");
  s.section("distributed", &SearchCommandOptions::distributed, distributed::distributed_schema(),
            "train candidates on several processes or machines (docs/distributed.md)");
  add_run_settings(s);
  return s;
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
  Model parent = load_model(options.parent);
  // Candidates read a subset of the parent's channels (their geometry targets too, at HR).
  const Dataset data = open_for_channels(options.data, parent.network->input_channels());
  if (!parent.network->has_rit())
    spdlog::warn("{}: the parent has no RIT block; the search runs on the plain backbone", options.parent);

  std::vector<int> drop_order;
  if (options.search.space.drop_blocks == BlockDrop::Importance && parent.network->spec().blocks > 0) {
    drop_order = block_drop_order(*parent.network);
    spdlog::info("search: shallower candidates drop the parent's blocks in the order {} (least important first)",
                 fmt::join(drop_order, ", "));
  }
  TrainingEvaluator local(parent.network, data, options.candidate, drop_order);
  // Rank 0 opens the history before the others join: a refused --out fails before they wait.
  std::optional<SearchHistory> history;
  if (!options.distributed.enabled() || options.distributed.rank == 0)
    history.emplace(run_dir.file("history.jsonl"), options.resume);
  std::unique_ptr<distributed::World> world;
  std::optional<distributed::WorkQueue> queue;
  std::optional<DistributedEvaluator> distributed_evaluator;
  if (options.distributed.enabled()) {
    // What a candidate's score depends on: every rank must agree on it.
    const std::string job = std::to_string(fnv1a64(read_file(options.parent))) + "\n" +
                            std::to_string(data.frames(Split::Train).size()) + " " +
                            std::to_string(data.frames(Split::Val).size()) + "\n" + std::to_string(options.seed) +
                            "\n" + config::to_yaml(candidate_training_schema().emit(options.candidate));
    world = join_run(options.distributed, job);
    queue.emplace(*world);
    if (options.candidate.schedule.layout == MemoryLayout::Auto)
      spdlog::warn("candidate.schedule.layout is auto: each process measures its own memory layout, so a score can "
                   "differ in the last digits from a 1-process run (set nchw or nhwc for identical ones)");
    if (!world->coordinator()) {
      const int trained = serve_candidates(*queue, local);
      spdlog::info("distributed: {} trained {} candidate(s); rank 0 records the search", world->describe(), trained);
      nlohmann::ordered_json j;
      j["rank"] = world->rank();
      j["world_size"] = world->size();
      j["candidates_trained"] = trained;
      return j;
    }
    distributed_evaluator.emplace(local, *queue);
  }
  Evaluator& evaluator = distributed_evaluator ? static_cast<Evaluator&>(*distributed_evaluator) : local;

  SearchResult result;
  try {
    result = run_search(parent.network->spec(), evaluator, *history, options.search);
  } catch (const std::exception& e) {
    if (queue) queue->abort(e.what());
    throw;
  }
  if (queue) queue->finish();  // the other ranks return; rank 0 trains the pick alone
  write_population_plot(run_dir.file("population.png"), result);
  if (result.pick_is_parent)
    spdlog::warn("no candidate stayed within {} dB of the parent; the parent is kept", options.search.tolerance_db);

  // The CG-optimized network: the pick, inherited from the parent and trained longer.
  SRNetwork picked = inherit(*parent.network, result.pick.spec, {}, local.parent_blocks(result.pick.spec)).network;
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
  j["parent"] = {{"spec", spec_summary(result.parent.spec)}, {"score", result.parent.score}};
  j["pick"] = {{"spec", spec_summary(result.pick.spec)},
               {"spec_yaml", spec_to_yaml(result.pick.spec)},
               {"score", result.pick.score},
               {"is_parent", result.pick_is_parent}};
  j["param_reduction"] = reduction;
  j["pareto_front"] = nlohmann::ordered_json::array();
  for (const auto& c : pareto_front(result.evaluated))
    j["pareto_front"].push_back({{"spec", spec_summary(c.spec)}, {"params", c.score.params}, {"val_psnr", c.score.val_psnr}});
  j["candidates"] = result.evaluated.size();
  j["generations"] = result.generations_run;
  j["stop_reason"] = result.stop_reason;
  j["final_training"] = to_json(final_training);
  if (world) j["world_size"] = world->size();
  return j;
}

}  // namespace cgsr
