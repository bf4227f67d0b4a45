#include "pipeline/controls_stage.h"

#include <spdlog/spdlog.h>

#include "core/yaml_json.h"
#include "models/latency_table.h"
#include "models/model_file.h"
#include "render_data/dataset.h"
#include "render_data/patch_sampler.h"
#include "train/distillation.h"

namespace cgsr {

config::Schema<ControlsOptions> controls_schema() {
  config::Schema<ControlsOptions> s;
  s.field("kinds", &ControlsOptions::kinds, "controls cut to the final network's latency: magnitude (MMP), uniform");
  return s;
}

nlohmann::ordered_json run_controls(const ControlsJob& job, RunDir& run_dir, bool resume) {
  Model enhanced = load_model(job.enhanced);
  Model final_network = load_model(job.final_model);
  const Dataset data = open_for_channels(job.data, enhanced.network->input_channels());
  const Resolution lr = data.resolutions()[resolution_pair(data, enhanced.network->spec().scale).first];
  final_network.network->eval();
  const double target = measure_graph_latency(final_network.network->describe(false), lr.width, lr.height, /*runs=*/7);
  const std::string base = enhanced.provenance.extra.value("name", std::filesystem::path(job.enhanced).stem().string());
  spdlog::info("controls: cut {} to the latency of {} ({:.1f} ms at {}x{})", base, job.final_model, target, lr.width,
               lr.height);
  nlohmann::ordered_json results;
  results["target_latency_ms"] = target;
  results["controls"] = nlohmann::ordered_json::array();
  for (const ControlKind kind : job.options.kinds) {
    ControlNetwork control = control_at_latency(*enhanced.network, kind, target, measured_latency(lr.width, lr.height));
    const std::string name = base + " " + control_label(kind);
    const std::string stem = enum_name(kind);
    spdlog::info("{}: keep rate {:.3f}, {:.1f} ms; fine-tuning {} steps", name, control.rate, control.latency_ms,
                 job.schedule.steps);
    TrainHooks hooks;
    if (job.distill > 0) hooks = distillation_hooks(load_model(job.enhanced).network, job.distill, job.loss.image_norm);
    Trainer trainer(control.network, data, job.schedule, job.loss, {}, hooks);
    const TrainOutcome outcome = trainer.run(run_dir.file("finetune_" + stem + ".pt"), resume);
    Provenance p;
    p.stage = "control";
    p.parent = job.enhanced;
    p.metrics = {{"val_psnr", outcome.best.psnr}, {"val_ssim", outcome.best.ssim}};
    p.extra = {{"name", name}, {"data", data.info().root.string()}, {"control", stem}, {"keep_rate", control.rate}};
    const auto file = run_dir.file(stem + ".cgsr");
    save_model(file, *control.network, p);
    results["controls"].push_back({{"kind", stem},
                                   {"name", name},
                                   {"file", file.string()},
                                   {"keep_rate", control.rate},
                                   {"latency_ms", control.latency_ms},
                                   {"spec", spec_summary(control.network->spec())},
                                   {"training", to_json(outcome)}});
  }
  return results;
}

}  // namespace cgsr
