#include "pruning/pruner.h"

#include <spdlog/spdlog.h>
#include <torch/torch.h>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/progress.h"
#include "eval/pattern_choice.h"
#include "pruning/hybrid_upscaler.h"
#include "pruning/pattern_networks.h"
#include "render_data/patch_sampler.h"

namespace cgsr {

const PrunedBaseline* PruneRoles::baseline(const std::string& type) const {
  for (const auto& b : baselines)
    if (b.options.type == type) return &b;
  return nullptr;
}

nlohmann::ordered_json to_json(const PruneRoles& roles) {
  nlohmann::ordered_json j;
  j["input"] = roles.input;
  j["hybrid"] = roles.hybrid;
  j["static"] = roles.static_network;
  j["baselines"] = nlohmann::ordered_json::array();
  for (const auto& b : roles.baselines) {
    nlohmann::ordered_json entry = static_cast<const PrunedModel&>(b);
    entry["type"] = b.options.type;
    entry["requested_keep_rate"] = b.options.keep_rate;
    entry["keep_rate"] = b.keep_rate;
    j["baselines"].push_back(entry);
  }
  return j;
}

PruneRoles prune_roles_from_json(const nlohmann::ordered_json& j, const std::string& where) {
  PruneRoles roles;
  try {
    j.at("input").get_to(roles.input);
    j.at("hybrid").get_to(roles.hybrid);
    j.at("static").get_to(roles.static_network);
    for (const auto& b : j.at("baselines")) {
      PrunedBaseline baseline;
      b.get_to(static_cast<PrunedModel&>(baseline));
      baseline.options.type = b.at("type").get<std::string>();
      baseline.options.keep_rate = b.at("requested_keep_rate").get<double>();
      baseline.keep_rate = b.at("keep_rate").get<double>();
      roles.baselines.push_back(baseline);
    }
  } catch (const nlohmann::json::exception& e) {
    throw Error(where, std::string("malformed prune roles (run cgsr prune again): ") + e.what());
  }
  return roles;
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

// Per frame of `frames`, the importance of every unit channel of `net` under `method`.
std::vector<FrameImportance> importance_on(SRNetworkImpl& net, const Dataset& data, const std::vector<int>& frames,
                                           const std::string& method) {
  const auto groups = unit_groups(find_units(net.describe(false)));
  const ImportanceMethod& importance_method = importance_methods().get(method);
  std::vector<FrameImportance> out;
  Progress progress("importance (" + method + ")", static_cast<int64_t>(frames.size()));
  for (int f : frames) {
    out.push_back(importance_method.score(net, frame_batch(data, f, net.spec().scale, net.input_channels(), net.depth_encoding()), groups));
    progress.advance();
  }
  progress.finish();
  return out;
}

// Step 1: the input network with its unit channels in order of importance on `frames`, and the
// pool of nested patterns over it.
std::pair<SRNetwork, PatternPool> ordered_network(SRNetworkImpl& net, const Dataset& data, const std::vector<int>& frames,
                                                  const PruneOptions& options) {
  const auto units = find_units(net.describe(false));
  const auto importance = importance_on(net, data, frames, options.importance);
  SRNetwork ordered = order_channels(net, importance_order(units, importance)).network;
  PatternPool pool = nested_pool(find_units(ordered->describe(false)), options.pool.keep_rates);
  return {ordered, pool};
}

// Step 4: static pruning and the hybrid model with its latency table.
HybridModel hybrid_model(DynamicPruning& dynamic, const std::vector<int64_t>& counts, const Dataset& data, int frame,
                         const PruneOptions& options, StaticPruning& pruned) {
  pruned = static_prune(*dynamic.network(), dynamic.pool(), counts, options.static_prune);
  HybridModel hybrid;
  hybrid.network = pruned.network;
  hybrid.pool = pruned.pool;
  hybrid.samplers = dynamic.samplers();
  hybrid.samplers->keep_patterns({pruned.kept});
  PatternNetworks patterns(*hybrid.network, hybrid.pool);
  const Batch b = frame_batch(data, frame, hybrid.network->spec().scale, hybrid.network->input_channels(),
                              hybrid.network->depth_encoding());
  hybrid.latency.lr_width = b.lr_color.size(3);
  hybrid.latency.lr_height = b.lr_color.size(2);
  for (const auto& l : patterns.measure_latency(b.lr_color, hybrid.network->info_input(b), options.selector.latency_runs))
    hybrid.latency.median_ms.push_back(l.median_ms);
  return hybrid;
}

// The MACs of the hybrid model's choices on the training frames, averaged per frame.
double mean_chosen_macs(const HybridModel& hybrid, const StaticPruning& pruned, const std::vector<int64_t>& counts,
                        const Resolution& lr) {
  PatternNetworks patterns(*hybrid.network, hybrid.pool);
  double macs = 0;
  int64_t chosen = 0;
  for (size_t i = 0; i < pruned.kept.size(); ++i) {
    const int64_t n = counts[pruned.kept[i]];
    macs += static_cast<double>(n) * static_cast<double>(patterns.cost(static_cast<int>(i), lr.width, lr.height).macs);
    chosen += n;
  }
  return macs / static_cast<double>(std::max<int64_t>(1, chosen));
}

// What every static baseline of one prune run shares.
struct BaselineContext {
  std::filesystem::path model_path;  // the input model
  const Dataset& data;
  std::vector<int> frames;  // the frames that rank channels
  TrainSchedule schedule;   // the hybrid model's fine-tuning steps
  LossOptions loss;
  std::filesystem::path out;
  bool resume = false;
  Provenance provenance;  // extra.name: the input model's display name
};

// Step 5: one static baseline of the input network, at its own rate or at `macs`, fine-tuned
// like the hybrid model (resumable from its checkpoint); its training outcome goes to `training`.
PrunedBaseline prune_baseline(const BaselineContext& c, const BaselineOptions& options, size_t index, double macs,
                              nlohmann::ordered_json& training) {
  Model input = load_model(c.model_path);
  SRNetworkImpl& net = *input.network;
  const Resolution lr = c.data.resolutions()[resolution_pair(c.data, net.spec().scale).first];
  PrunedBaseline b;
  b.options = options;
  b.keep_rate = options.keep_rate > 0 ? options.keep_rate
                                      : keep_rate_for_macs(net, static_cast<int64_t>(macs), lr.width, lr.height);
  b.name = c.provenance.extra.at("name").get<std::string>() + " " + baseline_label(options);
  const std::string stem = "baseline" + std::to_string(index) + "_" + options.type;
  b.file = c.out / (stem + ".cgsr");
  // A frame-independent method needs one frame.
  const auto ranked = importance_methods().get(options.type).same_on_every_frame ? std::vector<int>{c.frames.front()}
                                                                                 : c.frames;
  const auto order = importance_order(find_units(net.describe(false)), importance_on(net, c.data, ranked, options.type));
  Inheritance pruned = prune_to_rate(net, order, b.keep_rate);
  spdlog::info("fine-tuning the {} baseline ({}, keep rate {:.3f}): {} steps", options.type,
               spec_summary(pruned.network->spec()), b.keep_rate, c.schedule.steps);
  Trainer trainer(pruned.network, c.data, c.schedule, c.loss);
  const TrainOutcome outcome = trainer.run(c.out / ("finetune_" + stem + ".pt"), c.resume);
  Provenance p = c.provenance;
  p.stage = "pruned-baseline";
  p.metrics = {{"val_psnr", outcome.best.psnr}, {"val_ssim", outcome.best.ssim}};
  p.extra["name"] = b.name;
  p.extra["baseline"] = options.type;
  p.extra["keep_rate"] = b.keep_rate;
  save_model(b.file, *pruned.network, p);
  training[stem] = to_json(outcome);
  return b;
}

// Step 2: every pattern of the pool fine-tuned by the sandwich rule (resumable).
TrainOutcome finetune_patterns(SRNetwork& net, DynamicPruning& dynamic, const Dataset& data, const PruneOptions& options,
                               const TrainSchedule& schedule, const std::filesystem::path& out, bool resume) {
  spdlog::info("fine-tuning {} nested patterns: {} steps ({} epochs)", dynamic.pool().size(), schedule.steps,
               options.finetune.epochs);
  Trainer finetune(net, data, schedule, options.finetune.loss, {}, dynamic.hooks(options.finetune));
  return finetune.run(out / "finetune_hybrid.pt", resume);
}

// Step 6: the input network, the baselines, the static network and the hybrid model (read back
// from its file) evaluated through the same code path as `cgsr eval`; the hybrid's per-pattern
// test usage goes to `test_usage`.
std::vector<EvalResult> evaluate_roles(const PruneRoles& roles, const StaticPruning& pruned, size_t patterns,
                                       const Dataset& data, const EvalOptions& eval, std::vector<int>& test_usage) {
  std::vector<EvalResult> evaluations;
  {
    NetworkUpscaler dense(roles.input.name, load_model(roles.input.file).network);
    evaluations.push_back(evaluate(dense, data, eval));
  }
  for (const auto& b : roles.baselines) {
    NetworkUpscaler baseline(b.name, load_model(b.file).network);
    evaluations.push_back(evaluate(baseline, data, eval));
  }
  {
    NetworkUpscaler static_only(roles.static_network.name, pruned.network);
    evaluations.push_back(evaluate(static_only, data, eval));
  }
  HybridUpscaler from_file(roles.hybrid.name, load_hybrid_model(roles.hybrid.file));
  evaluations.push_back(evaluate(from_file, data, eval));
  // Per pattern, the evaluated frames that chose it (the upscaler also ran frames before them,
  // for the temporal error).
  test_usage.assign(patterns, 0);
  if (const auto choices = pattern_choices(evaluations.back()))
    for (const auto& [k, n] : choices->usage) test_usage.at(k) = n;
  return evaluations;
}

// The evaluations and each one's difference to the first (the input network), also logged.
void add_evaluations(nlohmann::ordered_json& results, const std::vector<EvalResult>& evaluations) {
  results["evaluations"] = nlohmann::ordered_json::array();
  results["comparison"] = nlohmann::ordered_json::array();
  for (const auto& r : evaluations) {
    results["evaluations"].push_back(to_json(r));
    results["comparison"].push_back(against(r, evaluations.front()));
    spdlog::info("{}: PSNR {:.3f} dB, SSIM {:.4f}, params {}, MACs {}{}", r.name, r.psnr, r.ssim,
                 r.cost ? format_count(static_cast<double>(r.cost->params)) : "-",
                 r.cost ? format_count(static_cast<double>(r.cost->macs)) : "-",
                 r.latency ? ", " + std::to_string(r.latency->median_ms) + " ms" : "");
  }
}

// The input model, checked for what pruning needs, and its display name.
Model load_prunable(const std::filesystem::path& model_path, const Dataset& data, const PruneOptions& options,
                    std::string& name) {
  const std::string where = model_path.string();
  if (!is_model_file(model_path)) throw Error(where, "not a trained model file (cgsr prune needs trained weights)");
  Model input = load_model(model_path);
  name = options.name.empty() ? input.provenance.extra.value("name", model_path.stem().string()) : options.name;
  if (find_units(input.network->describe(false)).empty())
    throw Error(where, "the network has no layer groups that can be pruned per frame");
  if (data.frames(Split::Train).empty()) throw Error(data.info().root.string(), "the data set has no training frames");
  return input;
}
}  // namespace

nlohmann::ordered_json prune(const std::filesystem::path& model_path, const Dataset& data, const PruneOptions& options,
                             const std::filesystem::path& out, bool resume, const nlohmann::ordered_json& config) {
  const std::string where = model_path.string();
  std::string name;
  Model input = load_prunable(model_path, data, options, name);
  const int scale = input.network->spec().scale;
  const auto train_frames = data.frames(Split::Train);
  spdlog::info("pruning {} ({}): {} patterns of keep rates {}", name, spec_summary(input.network->spec()),
               options.pool.keep_rates.size(), nlohmann::json(options.pool.keep_rates).dump());
  PruneRoles roles;
  roles.input = {name, model_path};

  // 1. Channels in order of importance, nested patterns.
  const auto pool_frames = spread_frames(train_frames, options.pool_frames);
  auto [net, pool] = ordered_network(*input.network, data, pool_frames, options);
  write_file_atomic(out / "pool.json", to_json(pool).dump(1));

  // 2. Every pattern fine-tuned (sandwich rule).
  DynamicPruning dynamic(net, data, pool, options.sampler);
  TrainSchedule schedule = options.finetune.schedule;
  schedule.steps = finetune_steps(options.finetune, data, scale);
  const TrainOutcome hybrid_training = finetune_patterns(net, dynamic, data, options, schedule, out, resume);

  // 3. The per-frame choice.
  const SelectorFit fit = dynamic.fit_selector(spread_frames(train_frames, options.selector.frames), options.selector);
  spdlog::info("pattern choice fitted: mean cost {:.3f} of the widest (budget {}), {:.0f}% of the frames' cheapest "
               "patterns chosen",
               fit.mean_cost, options.selector.budget, 100 * fit.agreement);

  // 4. Static pruning of what no training frame selects.
  const auto counts = dynamic.selection_counts(train_frames);
  StaticPruning pruned;
  HybridModel hybrid = hybrid_model(dynamic, counts, data, train_frames.front(), options, pruned);
  hybrid.provenance.stage = "pruned";
  hybrid.provenance.parent = where;
  hybrid.provenance.config = config;
  hybrid.provenance.metrics = {{"val_psnr", hybrid_training.best.psnr}, {"val_ssim", hybrid_training.best.ssim}};
  hybrid.provenance.extra = {{"name", name + " hybrid"}, {"data", data.info().root.string()},
                             {"left_out", pruned.left_out}};
  roles.hybrid = {name + " hybrid", out / "pruned.cgsr"};
  roles.static_network = {name + " static", roles.hybrid.file};
  save_hybrid_model(roles.hybrid.file, hybrid);
  const Resolution lr = data.resolutions()[resolution_pair(data, scale).first];
  const double mean_macs = mean_chosen_macs(hybrid, pruned, counts, lr);

  nlohmann::ordered_json results;
  results["model"] = where;
  results["name"] = name;
  results["data"] = data.info().root.string();
  results["spec"] = spec_summary(input.network->spec());
  results["pruned_spec"] = spec_summary(pruned.network->spec());
  results["pool"] = to_json(pool);
  results["keep_rates"] = options.pool.keep_rates;
  results["selected_per_pattern"] = counts;
  results["latency_table"] = {{"lr_size", {hybrid.latency.lr_width, hybrid.latency.lr_height}},
                              {"median_ms", hybrid.latency.median_ms}};
  results["importance"] = options.importance;
  results["pool_frames"] = pool_frames.size();
  results["selector"] = to_json(fit);
  results["mean_macs_train"] = mean_macs;
  results["left_out"] = pruned.left_out;
  results["finetune"] = {{"steps", schedule.steps}, {"hybrid", to_json(hybrid_training)}};

  // 5. The static baselines, at the hybrid model's mean MACs unless given a rate, same steps.
  BaselineContext context{model_path, data, pool_frames, schedule, options.finetune.loss, out, resume, {}};
  context.provenance.parent = where;
  context.provenance.config = config;
  context.provenance.extra = {{"name", name}, {"data", data.info().root.string()}};
  for (size_t i = 0; i < options.baselines.size(); ++i)
    roles.baselines.push_back(prune_baseline(context, options.baselines[i], i, mean_macs, results["finetune"]));
  results["roles"] = to_json(roles);

  // 6. Held-out evaluation through the same code path as `cgsr eval`.
  std::vector<int> test_usage;
  const auto evaluations = evaluate_roles(roles, pruned, hybrid.pool.size(), data, options.eval, test_usage);
  results["test_selected_per_pattern"] = test_usage;
  add_evaluations(results, evaluations);
  return results;
}

}  // namespace cgsr
