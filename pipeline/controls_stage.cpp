#include "pipeline/controls_stage.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <set>

#include "core/atomic_file.h"
#include "core/yaml_json.h"
#include "eval/relative_latency.h"
#include "models/model_file.h"
#include "render_data/dataset.h"
#include "render_data/patch_sampler.h"
#include "train/distillation.h"

namespace cgsr {

config::Schema<ControlsOptions> controls_schema() {
  config::Schema<ControlsOptions> s;
  s.field("kinds", &ControlsOptions::kinds, "controls cut to the final network's latency: magnitude (MMP), uniform");
  s.field("latency_factors", &ControlsOptions::latency_factors,
          "latencies each kind is cut to, as multiples of the final network's (1: equal latency)");
  s.validate([](const ControlsOptions& o, const config::Cursor& at, const YAML::Node& node) {
    if (o.latency_factors.empty()) at.child("latency_factors").fail(node["latency_factors"], "must list a factor");
    std::set<double> seen;
    for (double f : o.latency_factors) {
      if (!(f > 0 && f <= 4))
        at.child("latency_factors").fail(node["latency_factors"], fmt::format("{:g} is not in (0, 4]", f));
      if (!seen.insert(f).second)
        at.child("latency_factors").fail(node["latency_factors"], fmt::format("{:g} is listed twice", f));
    }
  });
  return s;
}

namespace {
constexpr int kTimedRuns = 7;      // interleaved rounds per control timed
constexpr double kReached = 1.05;  // a cut within 5% of its latency target reaches it (timing noise)

// The control's file stem: its kind, and its latency factor when that is not 1.
std::string control_stem(ControlKind kind, double latency_factor) {
  return enum_name(kind) + (latency_factor == 1.0 ? "" : fmt::format("_x{:g}", latency_factor));
}

// Its display name: the factor is said when it is not 1.
std::string control_name(const std::string& base, ControlKind kind, double latency_factor) {
  return base + " " + control_label(kind) + (latency_factor == 1.0 ? "" : fmt::format(" at {:g}x", latency_factor));
}

// The control of `kind` at `factor` times the final network's latency: cut by timing, or, in a
// resumed run, where its kept cut says. The cut is kept: timings differ between runs, and a
// resumed fine-tuning needs its network.
ControlNetwork cut_control(const SRNetworkImpl& enhanced, ControlKind kind, double factor, const NetworkCost& fraction,
                           const std::filesystem::path& cut_file, bool resume) {
  if (resume && std::filesystem::exists(cut_file)) {
    const auto cut = nlohmann::json::parse(read_file(cut_file));
    const double cost = cut.at("latency_fraction").get<double>();
    return control_at_rate(enhanced, kind, cut.at("keep_rate").get<double>(), [&](const SRNetwork&) { return cost; });
  }
  ControlNetwork control = control_at_latency(enhanced, kind, factor, fraction);
  write_file_atomic(cut_file,
                    nlohmann::json{{"keep_rate", control.rate}, {"latency_fraction", control.cost}}.dump() + "\n");
  return control;
}

// Fine-tunes the control like the final network and saves it as <stem>.cgsr; its results entry.
nlohmann::ordered_json finetune_control(const ControlsJob& job, const Dataset& data, RunDir& run_dir, bool resume,
                                        const ControlNetwork& control, ControlKind kind, double factor,
                                        const std::string& name, const std::string& stem) {
  TrainHooks hooks;
  if (job.distill > 0) hooks = distillation_hooks(load_model(job.enhanced).network, job.distill, job.loss.image_norm);
  Trainer trainer(control.network, data, job.schedule, job.loss, {}, hooks);
  const TrainOutcome outcome = trainer.run(run_dir.file("finetune_" + stem + ".pt"), resume);
  Provenance p;
  p.stage = "control";
  p.parent = job.enhanced;
  p.metrics = {{"val_psnr", outcome.best.psnr}, {"val_ssim", outcome.best.ssim}};
  p.extra = {{"name", name}, {"data", data.info().root.string()}, {"control", enum_name(kind)},
             {"latency_factor", factor}, {"keep_rate", control.rate}};
  const auto file = run_dir.file(stem + ".cgsr");
  save_model(file, *control.network, p);
  return {{"kind", enum_name(kind)},
          {"latency_factor", factor},
          {"name", name},
          {"file", file.string()},
          {"keep_rate", control.rate},
          {"latency_fraction", control.cost},
          {"spec", spec_summary(control.network->spec())},
          {"training", to_json(outcome)}};
}
}  // namespace

nlohmann::ordered_json run_controls(const ControlsJob& job, RunDir& run_dir, bool resume) {
  Model enhanced = load_model(job.enhanced);
  Model final_network = load_model(job.final_model);
  const Dataset data = open_for_channels(job.data, enhanced.network->input_channels());
  const std::string base = enhanced.provenance.extra.value("name", std::filesystem::path(job.enhanced).stem().string());
  const std::string final_name =
      final_network.provenance.extra.value("name", std::filesystem::path(job.final_model).stem().string());
  // Matched on latency as the report measures it: against the final network, in interleaved rounds.
  const LatencyReference timer(std::make_unique<NetworkUpscaler>(final_name, final_network.network), data,
                               data.frames(Split::Val), kTimedRuns);
  const NetworkCost fraction = [&](const SRNetwork& network) {
    NetworkUpscaler upscaler("control", network);
    return timer.time(upscaler).fraction();
  };
  spdlog::info("controls: cut {} to the latency of {}", base, final_name);
  nlohmann::ordered_json results;
  results["latency_of"] = job.final_model;
  results["controls"] = nlohmann::ordered_json::array();
  // Equal latency first: when a kind cannot be cut as far as a smaller factor asks, that cut is
  // the same network, kept once under the equal-latency control's name.
  std::vector<double> factors = job.options.latency_factors;
  std::stable_partition(factors.begin(), factors.end(), [](double f) { return f == 1.0; });
  for (const ControlKind kind : job.options.kinds) {
    std::set<double> rates_cut;
    for (const double factor : factors) {
      const std::string name = control_name(base, kind, factor);
      const std::string stem = control_stem(kind, factor);
      const ControlNetwork control =
          cut_control(*enhanced.network, kind, factor, fraction, run_dir.file("cut_" + stem + ".json"), resume);
      if (!rates_cut.insert(control.rate).second) {
        spdlog::warn("{}: the same cut as another {} control (keep rate {:.3f}, {:.2f}x {}'s latency); not trained "
                     "again", name, control_label(kind), control.rate, control.cost, final_name);
        continue;
      }
      if (control.cost > factor * kReached)
        spdlog::warn("{}: its narrowest cut runs at {:.2f}x {}'s latency, above the {:g}x asked for", name,
                     control.cost, final_name, factor);
      spdlog::info("{}: keep rate {:.3f}, {:.2f}x {}'s latency; fine-tuning {} steps", name, control.rate, control.cost,
                   final_name, job.schedule.steps);
      results["controls"].push_back(finetune_control(job, data, run_dir, resume, control, kind, factor, name, stem));
    }
  }
  return results;
}

}  // namespace cgsr
