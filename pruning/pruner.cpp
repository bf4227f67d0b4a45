#include "pruning/pruner.h"

#include <spdlog/spdlog.h>
#include <torch/torch.h>

#include "core/atomic_file.h"
#include "core/error.h"
#include "eval/pattern_choice.h"
#include "models/latency_table.h"
#include "pruning/hybrid_upscaler.h"
#include "pruning/pattern_networks.h"
#include "pruning/static_pruning.h"
#include "render_data/patch_sampler.h"
#include "search/evaluator.h"
#include "search/search_loop.h"
#include "train/elastic_training.h"

namespace cgsr {

config::Schema<PoolTraining> pool_training_schema() {
  config::Schema<PoolTraining> s;
  s.section("schedule", &PoolTraining::schedule, schedule_schema(), "optimization schedule");
  s.section("loss", &PoolTraining::loss, loss_schema(), "its loss");
  s.field("distill", &PoolTraining::distill, "weight of the full elastic network's output beside the HR frame's")
      .range(0, 1);
  return s;
}

PruneRoles prune_roles_from_json(const nlohmann::ordered_json& j, const std::string& where) {
  try {
    return j.get<PruneRoles>();
  } catch (const nlohmann::json::exception& e) {
    throw Error(where, std::string("malformed prune roles (run cgsr prune again): ") + e.what());
  }
}

namespace {
// Ratios of a model's figures to the input model's (same frames, same process).
nlohmann::ordered_json against(const EvalResult& r, const EvalResult& base) {
  nlohmann::ordered_json j;
  j["name"] = r.name;
  if (r.cost && base.cost) {
    j["params_ratio"] = static_cast<double>(r.cost->params) / static_cast<double>(base.cost->params);
    j["macs_ratio"] = static_cast<double>(r.cost->macs) / static_cast<double>(base.cost->macs);
  }
  if (r.latency && base.latency) j["latency_ratio"] = r.latency->median_ms / base.latency->median_ms;
  j["psnr_delta_db"] = r.psnr - base.psnr;
  j["ssim_delta"] = r.ssim - base.ssim;
  return j;
}

// What the search left for pruning: its front (evolution's), its pick and the pick's file.
struct SearchOutcome {
  std::vector<Candidate> front;
  Candidate pick;
  std::filesystem::path pick_file;
  std::string pick_name;
};

SearchOutcome read_search(const std::filesystem::path& path) {
  const std::string where = path.string();
  SearchOutcome s;
  try {
    const auto j = nlohmann::ordered_json::parse(read_file(path));
    const auto read = [&](const nlohmann::ordered_json& c, const std::string& what) {
      Candidate out;
      out.subnet = subnet_from_json(c.at("subnet"), where + ": " + what);
      out.key = c.at("key").get<std::string>();
      out.score = c.at("score").get<SubnetScore>();
      out.quality = c.at("quality").get<double>();
      return out;
    };
    const auto& searches = j.at("searches");
    if (!searches.is_object() || searches.empty()) throw Error(where, "no search in the results");
    for (const auto& c : searches.begin().value().at("front")) s.front.push_back(read(c, "front"));
    s.pick = read(j.at("pick"), "pick");
    s.pick_file = j.at("model").get<std::string>();
    s.pick_name = j.at("name").get<std::string>();
  } catch (const nlohmann::json::exception& e) {
    throw Error(where, std::string("not a cgsr search results file: ") + e.what());
  }
  return s;
}

// The evaluations and each one's difference to the first (the input network), also logged.
void add_evaluations(nlohmann::ordered_json& results, const std::vector<EvalResult>& evaluations) {
  results["evaluations"] = nlohmann::ordered_json::array();
  results["comparison"] = nlohmann::ordered_json::array();
  for (const auto& r : evaluations) {
    results["evaluations"].push_back(to_json(r));
    results["comparison"].push_back(against(r, evaluations.front()));
    spdlog::info("{}: PSNR {:.3f} dB, SSIM {:.4f}, params {}, MACs {}", r.name, r.psnr, r.ssim,
                 r.cost ? format_count(static_cast<double>(r.cost->params)) : "-",
                 r.cost ? format_count(static_cast<double>(r.cost->macs)) : "-");
  }
}
}  // namespace

nlohmann::ordered_json prune(const std::filesystem::path& elastic_path, const std::filesystem::path& search_path,
                             const Dataset& data, const PruneOptions& options, const std::filesystem::path& out,
                             bool resume, const nlohmann::ordered_json& config) {
  Model elastic = load_model(elastic_path);
  elastic.network->eval();
  const auto tables = latency_tables_from(elastic.provenance.extra, elastic_path.string());
  if (!tables.count(Precision::Fp32))
    throw Error(elastic_path.string(), "has no latency table (train it with elastic.enabled)");
  const LatencyTable& table = tables.at(Precision::Fp32);
  SearchOutcome search = read_search(search_path);
  // The hybrid runs in float32: the search's subnets in other precisions are priced as float32
  // (same structure, quality within the search's quantization loss) and the front taken again.
  const auto as_fp32 = [&](Candidate& c) {
    if (c.subnet.precision == Precision::Fp32) return;
    c.subnet.precision = Precision::Fp32;
    c.key = subnet_key(c.subnet);
    c.score.latency_ms = table.predict(subnet_graph(*elastic.network, c.subnet));
  };
  for (auto& c : search.front) as_fp32(c);
  search.front = latency_front(search.front);
  as_fp32(search.pick);
  const std::string name = options.name.empty() ? search.pick_name : options.name;
  const auto train_frames = data.frames(Split::Train);
  if (train_frames.empty()) throw Error(data.info().root.string(), "the data set has no training frames");
  PruneRoles roles;
  roles.input = {name, search.pick_file};

  // 1-2. The pool around the pick, in the network holding it, every pattern fine-tuned at once.
  const PatternPool pool = pool_from_front(elastic.network->spec(), search.front, search.pick.score.latency_ms,
                                           options.pool);
  const SubnetConfig all = pool_union(pool);
  SRNetwork net = materialize_subnet(*elastic.network, all, /*geometry_head=*/false);
  PatternPool in_net = rebase_pool(pool, all, net->spec());
  write_file_atomic(out / "pool.json", to_json(pool).dump(1));
  spdlog::info("pruning around {}: {} patterns of the front, from {:.1f} to {:.1f} ms predicted (the pick {:.1f} ms)",
               name, pool.size(), table.predict(subnet_graph(*elastic.network, pool.patterns.front())),
               table.predict(subnet_graph(*elastic.network, pool.patterns.back())), search.pick.score.latency_ms);
  nlohmann::ordered_json results;
  {
    const auto patterns = in_net.patterns;
    Trainer trainer(net, data, options.finetune.schedule, options.finetune.loss, {},
                    subnet_training_hooks(
                        net, [patterns](int) { return patterns; }, options.finetune.distill, options.finetune.loss,
                        elastic.network));
    results["finetune"] = to_json(trainer.run(out / "finetune_patterns.pt", resume));
  }
  net->eval();

  // 3. The per-frame choice, at the pick's latency on average unless a budget is given.
  SelectorOptions selector = options.selector;
  if (selector.budget <= 0)
    selector.budget = std::min(1.0, search.pick.score.latency_ms / table.predict(subnet_graph(*net, in_net.patterns.front())));
  DynamicPruning dynamic(net, data, in_net, options.sampler);
  const SelectorFit fit = dynamic.fit_selector(spread_frames(train_frames, selector.frames), selector, &table);
  spdlog::info("pattern choice fitted: mean cost {:.3f} of the widest (budget {:.3f}), {:.0f}% of the frames' cheapest "
               "patterns chosen",
               fit.mean_cost, selector.budget, 100 * fit.agreement);

  // 4. Static pruning of what no training frame selects, and the hybrid model.
  const auto counts = dynamic.selection_counts(train_frames);
  const StaticPruning pruned = static_prune(*net, in_net, counts);
  HybridModel hybrid;
  hybrid.network = pruned.network;
  hybrid.pool = pruned.pool;
  hybrid.samplers = dynamic.samplers();
  hybrid.samplers->keep_patterns({pruned.kept});
  {
    PatternNetworks patterns(*hybrid.network, hybrid.pool);
    const Batch b = frame_batch(data, train_frames.front(), hybrid.network->spec().scale,
                                hybrid.network->input_channels(), hybrid.network->depth_encoding());
    hybrid.latency.lr_width = b.lr_color.size(3);
    hybrid.latency.lr_height = b.lr_color.size(2);
    for (const auto& l : patterns.measure_latency(b.lr_color, hybrid.network->info_input(b), selector.latency_runs))
      hybrid.latency.median_ms.push_back(l.median_ms);
  }
  hybrid.provenance.stage = "pruned";
  hybrid.provenance.parent = elastic_path.string();
  hybrid.provenance.config = config;
  hybrid.provenance.extra = {{"name", name + " hybrid"}, {"data", data.info().root.string()},
                             {"left_out", pruned.left_out}};
  roles.hybrid = {name + " hybrid", out / "pruned.cgsr"};
  roles.static_network = {name + " static", roles.hybrid.file};
  save_hybrid_model(roles.hybrid.file, hybrid);

  results["elastic"] = elastic_path.string();
  results["search"] = search_path.string();
  results["name"] = name;
  results["data"] = data.info().root.string();
  results["pruned_spec"] = spec_summary(pruned.network->spec());
  results["pool"] = to_json(pool);
  results["selected_per_pattern"] = counts;
  results["latency_ms"] = hybrid.latency.median_ms;
  results["selector"] = to_json(fit);
  results["left_out"] = pruned.left_out;
  results["roles"] = roles;

  // 5. Held-out evaluation through the same code path as `cgsr eval`.
  std::vector<EvalResult> evaluations;
  {
    NetworkUpscaler pick(roles.input.name, load_model(roles.input.file).network);
    evaluations.push_back(evaluate(pick, data, options.eval));
    NetworkUpscaler static_only(roles.static_network.name, pruned.network);
    evaluations.push_back(evaluate(static_only, data, options.eval));
    HybridUpscaler from_file(roles.hybrid.name, load_hybrid_model(roles.hybrid.file));
    evaluations.push_back(evaluate(from_file, data, options.eval));
  }
  std::vector<int64_t> test_usage(hybrid.pool.size(), 0);
  if (const auto choices = pattern_choices(evaluations.back()))
    for (const auto& [k, n] : choices->usage) test_usage.at(k) = n;
  results["test_selected_per_pattern"] = test_usage;
  add_evaluations(results, evaluations);
  return results;
}

}  // namespace cgsr
