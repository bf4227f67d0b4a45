#include "pruning/pruner.h"

#include <spdlog/spdlog.h>
#include <torch/torch.h>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/progress.h"
#include "pruning/activation_importance.h"
#include "pruning/hybrid_upscaler.h"
#include "pruning/magnitude_pruning.h"
#include "pruning/pattern_networks.h"
#include "render_data/patch_sampler.h"

namespace cgsr {

namespace {
std::vector<int> spread(const std::vector<int>& frames, int count) {
  if (count <= 0 || static_cast<size_t>(count) >= frames.size()) return frames;
  std::vector<int> out;
  for (int i = 0; i < count; ++i) out.push_back(frames[i * frames.size() / count]);
  return out;
}

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

// Step 1: the input network with its unit channels in order of importance on `frames`, and the
// pool of nested patterns over it.
std::pair<SRNetwork, PatternPool> ordered_network(SRNetworkImpl& net, const Dataset& data, const std::vector<int>& frames,
                                                  const PruneOptions& options) {
  const int scale = net.spec().scale;
  const auto units = find_units(net.describe(false));
  const auto method = enum_from_name<ImportanceMethod>(options.importance);
  std::vector<FrameImportance> importance;
  Progress progress("importance", static_cast<int64_t>(frames.size()));
  for (int f : frames) {
    importance.push_back(
        frame_importance(net, frame_batch(data, f, scale, net.input_channels(), net.depth_encoding()), units, method));
    progress.advance();
  }
  progress.finish();
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
}  // namespace

nlohmann::ordered_json prune(const std::filesystem::path& model_path, const Dataset& data, const PruneOptions& options,
                             const std::filesystem::path& out, bool resume, const nlohmann::ordered_json& config) {
  const std::string where = model_path.string();
  if (!is_model_file(model_path)) throw Error(where, "not a trained model file (cgsr prune needs trained weights)");
  Model input = load_model(model_path);
  const std::string name =
      options.name.empty() ? input.provenance.extra.value("name", model_path.stem().string()) : options.name;
  const int scale = input.network->spec().scale;
  if (find_units(input.network->describe(false)).empty())
    throw Error(where, "the network has no layer groups that can be pruned per frame");
  const auto train_frames = data.frames(Split::Train);
  if (train_frames.empty()) throw Error(data.info().root.string(), "the data set has no training frames");
  spdlog::info("pruning {} ({}): {} patterns of keep rates {}", name, spec_summary(input.network->spec()),
               options.pool.keep_rates.size(), nlohmann::json(options.pool.keep_rates).dump());

  // 1. Channels in order of importance, nested patterns.
  const auto pool_frames = spread(train_frames, options.pool_frames);
  auto [net, pool] = ordered_network(*input.network, data, pool_frames, options);
  write_file_atomic(out / "pool.json", to_json(pool).dump(1));

  // 2. Every pattern fine-tuned (sandwich rule).
  DynamicPruning dynamic(net, data, pool, options.sampler);
  TrainSchedule schedule = options.finetune.schedule;
  schedule.steps = finetune_steps(options.finetune, data, scale);
  spdlog::info("fine-tuning {} nested patterns: {} steps ({} epochs)", pool.size(), schedule.steps,
               options.finetune.epochs);
  Trainer finetune(net, data, schedule, options.finetune.loss, {}, dynamic.hooks(options.finetune));
  const TrainOutcome hybrid_training = finetune.run(out / "finetune_hybrid.pt", resume);

  // 3. The per-frame choice.
  const SelectorFit fit = dynamic.fit_selector(spread(train_frames, options.selector.frames), options.selector);
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
  const auto hybrid_path = out / "pruned.cgsr";
  save_hybrid_model(hybrid_path, hybrid);

  // Mean MACs of the hybrid model's choices on the training frames.
  const Resolution lr = data.resolutions()[resolution_pair(data, scale).first];
  PatternNetworks static_patterns(*hybrid.network, hybrid.pool);
  double mean_macs = 0;
  int64_t chosen = 0;
  for (size_t i = 0; i < pruned.kept.size(); ++i) {
    const int64_t n = counts[pruned.kept[i]];
    mean_macs += static_cast<double>(n) * static_cast<double>(static_patterns.cost(static_cast<int>(i), lr.width, lr.height).macs);
    chosen += n;
  }
  mean_macs /= static_cast<double>(std::max<int64_t>(1, chosen));

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
  results["files"] = {{"hybrid", hybrid_path.string()}, {"pool", (out / "pool.json").string()}};

  // 5. The magnitude pruning baseline at the hybrid model's mean MACs, same steps.
  Model original = load_model(model_path);
  std::optional<SRNetwork> mmp;
  if (options.magnitude_baseline) {
    const double rate = magnitude_rate_for_macs(*original.network, static_cast<int64_t>(mean_macs), lr.width, lr.height);
    Inheritance baseline = magnitude_prune(*original.network, rate);
    spdlog::info("fine-tuning the magnitude pruning baseline ({}, keep rate {:.3f}): {} steps",
                 spec_summary(baseline.network->spec()), rate, schedule.steps);
    Trainer trainer(baseline.network, data, schedule, options.finetune.loss);
    const TrainOutcome outcome = trainer.run(out / "finetune_mmp.pt", resume);
    Provenance p;
    p.stage = "pruned-magnitude";
    p.parent = where;
    p.config = config;
    p.metrics = {{"val_psnr", outcome.best.psnr}, {"val_ssim", outcome.best.ssim}};
    p.extra = {{"name", name + " MMP"}, {"data", data.info().root.string()}, {"keep_rate", rate}};
    save_model(out / "mmp.cgsr", *baseline.network, p);
    results["finetune"]["mmp"] = to_json(outcome);
    results["files"]["mmp"] = (out / "mmp.cgsr").string();
    results["mmp_keep_rate"] = rate;
    mmp = baseline.network;
  }
  // 6. Held-out evaluation through the same code path as `cgsr eval`.
  std::vector<EvalResult> evaluations;
  {
    NetworkUpscaler dense(name, original.network);
    evaluations.push_back(evaluate(dense, data, options.eval));
  }
  if (mmp) {
    NetworkUpscaler baseline(name + " MMP", *mmp);
    evaluations.push_back(evaluate(baseline, data, options.eval));
  }
  {
    NetworkUpscaler static_only(name + " static", pruned.network);
    evaluations.push_back(evaluate(static_only, data, options.eval));
  }
  {
    HybridUpscaler from_file(name + " hybrid", load_hybrid_model(hybrid_path));
    evaluations.push_back(evaluate(from_file, data, options.eval));
    std::vector<int64_t> usage(hybrid.pool.size(), 0);
    for (const auto& f : evaluations.back().frames) ++usage.at(f.details.at("pattern").get<int>());
    results["test_selected_per_pattern"] = usage;
  }
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
  return results;
}

}  // namespace cgsr
