#include "pruning/pruner.h"

#include <spdlog/spdlog.h>
#include <torch/torch.h>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/progress.h"
#include "pruning/activation_importance.h"
#include "pruning/hybrid_upscaler.h"
#include "pruning/magnitude_pruning.h"
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
}  // namespace

nlohmann::ordered_json prune(const std::filesystem::path& model_path, const Dataset& data, const PruneOptions& options,
                             const std::filesystem::path& out, bool resume, const nlohmann::ordered_json& config) {
  const std::string where = model_path.string();
  if (!is_model_file(model_path)) throw Error(where, "not a trained model file (cgsr prune needs trained weights)");
  Model input = load_model(model_path);
  const std::string name =
      options.name.empty() ? input.provenance.extra.value("name", model_path.stem().string()) : options.name;
  SRNetwork net = input.network;
  const int scale = net->spec().scale;
  const auto units = find_units(net->describe(false));
  if (units.empty()) throw Error(where, "the network has no layer groups that can be pruned per frame");
  const auto train_frames = data.frames(Split::Train);
  if (train_frames.empty()) throw Error(data.info().root.string(), "the data set has no training frames");
  spdlog::info("pruning {} ({}): {} units, keep rate {}, pool of {} per unit", name, spec_summary(net->spec()),
               units.size(), options.pool.keep_rate, options.pool.size);

  // 1-2. Per-frame importance, then the pattern pool.
  const auto pool_frames = spread(train_frames, options.pool_frames);
  const auto method = enum_from_name<ImportanceMethod>(options.importance);
  std::vector<FrameImportance> importance;
  {
    Progress progress("importance", static_cast<int64_t>(pool_frames.size()));
    for (int f : pool_frames) {
      importance.push_back(frame_importance(*net, frame_batch(data, f, scale, net->input_channels(), net->depth_encoding()), units, method));
      progress.advance();
    }
    progress.finish();
  }
  const PoolBuild build = build_pattern_pool(units, importance, options.pool);
  write_file_atomic(out / "pool.json", to_json(build.pool).dump(1));

  // 3. Dynamic samplers: warm-up, then fine-tuning of network and samplers with L_p.
  DynamicPruning dynamic(net, data, build.pool, options.sampler);
  const double warmup_accuracy =
      dynamic.warm_up(pool_frames, build.assignment, options.warmup_steps, options.warmup_lr);
  spdlog::info("samplers warmed up: {:.1f}% of the frames' pool entries predicted", 100 * warmup_accuracy);
  TrainSchedule schedule = options.finetune.schedule;
  schedule.steps = finetune_steps(options.finetune, data, scale);
  spdlog::info("fine-tuning with dynamic patterns: {} steps ({} epochs)", schedule.steps, options.finetune.epochs);
  Trainer finetune(net, data, schedule, options.finetune.loss, {}, dynamic.hooks(options.finetune, schedule.steps));
  const TrainOutcome hybrid_training = finetune.run(out / "finetune_hybrid.pt", resume);

  // 4. Static pruning of what no training frame selects.
  const auto counts = dynamic.selection_counts(train_frames);
  StaticPruning pruned = static_prune(*net, dynamic.pool(), counts, options.static_prune);
  DynamicSamplers samplers = dynamic.samplers();
  samplers->keep_patterns(pruned.kept);
  HybridModel hybrid;
  hybrid.network = pruned.network;
  hybrid.pool = pruned.pool;
  hybrid.samplers = samplers;
  hybrid.provenance.stage = "pruned";
  hybrid.provenance.parent = where;
  hybrid.provenance.config = config;
  hybrid.provenance.metrics = {{"val_psnr", hybrid_training.best.psnr}, {"val_ssim", hybrid_training.best.ssim}};
  hybrid.provenance.extra = {{"name", name + " hybrid"}, {"data", data.info().root.string()},
                             {"left_out", pruned.left_out}};
  const auto hybrid_path = out / "pruned.cgsr";
  save_hybrid_model(hybrid_path, hybrid);

  nlohmann::ordered_json results;
  results["model"] = where;
  results["name"] = name;
  results["data"] = data.info().root.string();
  results["spec"] = spec_summary(input.network->spec());
  results["pruned_spec"] = spec_summary(pruned.network->spec());
  auto units_json = nlohmann::ordered_json::array();
  for (size_t u = 0; u < units.size(); ++u) {
    nlohmann::ordered_json j;
    j["unit"] = units[u].name;
    j["groups"] = units[u].groups;
    j["widths"] = units[u].widths;
    j["pool_patterns"] = build.pool.units[u].patterns.size();
    j["selected_per_pattern"] = counts[u];
    units_json.push_back(j);
  }
  results["units"] = units_json;
  results["importance"] = options.importance;
  results["pool_frames"] = pool_frames.size();
  results["warmup_accuracy"] = warmup_accuracy;
  results["left_out"] = pruned.left_out;
  results["finetune"] = {{"steps", schedule.steps}, {"hybrid", to_json(hybrid_training)}};
  results["files"] = {{"hybrid", hybrid_path.string()}, {"pool", (out / "pool.json").string()}};

  // 5. The magnitude pruning baseline, same per-frame rate and budget.
  Model original = load_model(model_path);
  std::optional<SRNetwork> mmp;
  if (options.magnitude_baseline) {
    Inheritance baseline = magnitude_prune(*original.network, options.pool.keep_rate);
    spdlog::info("fine-tuning the magnitude pruning baseline ({}): {} steps", spec_summary(baseline.network->spec()),
                 schedule.steps);
    Trainer trainer(baseline.network, data, schedule, options.finetune.loss);
    const TrainOutcome outcome = trainer.run(out / "finetune_mmp.pt", resume);
    Provenance p;
    p.stage = "pruned-magnitude";
    p.parent = where;
    p.config = config;
    p.metrics = {{"val_psnr", outcome.best.psnr}, {"val_ssim", outcome.best.ssim}};
    p.extra = {{"name", name + " MMP"}, {"data", data.info().root.string()}};
    save_model(out / "mmp.cgsr", *baseline.network, p);
    results["finetune"]["mmp"] = to_json(outcome);
    results["files"]["mmp"] = (out / "mmp.cgsr").string();
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
