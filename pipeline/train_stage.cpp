#include "pipeline/train_stage.h"

#include <spdlog/spdlog.h>

#include "core/atomic_file.h"
#include "core/hash.h"
#include "core/yaml_json.h"
#include "models/complexity.h"
#include "models/elastic.h"
#include "models/inherit.h"
#include "models/latency_table.h"
#include "models/model_file.h"
#include "models/model_source.h"
#include "pipeline/distributed_run.h"
#include "render_data/dataset.h"
#include "train/quantization_aware.h"

namespace cgsr {

namespace {
config::Schema<EnhanceOptions> enhance_schema(bool with_enabled) {
  config::Schema<EnhanceOptions> s;
  if (with_enabled) s.field("enabled", &EnhanceOptions::enabled, "insert the RIT block (and geometry head) before training");
  s.section("rit", &EnhanceOptions::rit, rit_spec_schema(), "rendering information transform block");
  s.section("geometry", &EnhanceOptions::geometry, geometry_spec_schema(), "geometry head (training only)");
  return s;
}

// The keys of a training config, with `add_enhancement` adding the CG enhancement's in their place.
config::Schema<TrainOptions> train_schema_with(
    const std::function<void(config::Schema<TrainOptions>&)>& add_enhancement) {
  config::Schema<TrainOptions> s;
  s.field("data", &TrainOptions::data, "data set directory (cgsr render output or a described capture)").required();
  s.field("model", &TrainOptions::model, "backbone name, spec file or model file to start from");
  s.field("scale", &TrainOptions::scale, "upscaling factor (must match a model file)").range(2, 4);
  s.field("name", &TrainOptions::name, "display name in reports");
  add_enhancement(s);
  s.section("distill", &TrainOptions::distill, distill_schema(), "learn a teacher network's output too");
  config::Schema<QuantizationAwareOptions> qat;
  qat.field("enabled", &QuantizationAwareOptions::enabled, "train and validate through simulated INT8");
  qat.section("calibration", &QuantizationAwareOptions::calibration, calibration_schema_fields(),
              "the frames the INT8 activation ranges are measured on, before training");
  s.section("quantization_aware", &TrainOptions::quantization_aware, qat,
            "quantization-aware fine-tuning, for a network whose post-training INT8 loses too much");
  s.omit_when("quantization_aware", [](const TrainOptions& o) { return !o.quantization_aware.enabled; });
  s.section("schedule", &TrainOptions::schedule, schedule_schema(), "optimization schedule");
  s.section("loss", &TrainOptions::loss, loss_schema(), "CGSR loss weights");
  s.field("resume", &TrainOptions::resume, "continue from checkpoint.pt in the run directory");
  s.section("distributed", &TrainOptions::distributed, distributed::distributed_schema(),
            "data-parallel training on several processes or machines (docs/distributed.md)");
  add_run_settings(s);
  return s;
}

// `enabled` of an enhance block moved up from `enhance: enhance:` (older cgsr run configs): the
// stage always enhances, so it never meant anything there.
YAML::Node drop_enabled(const YAML::Node& map, const config::Cursor& at) {
  if (!map || !map.IsMap() || !map["enabled"]) return map;
  const std::string where = at.doc ? at.doc->locate(map["enabled"]) : at.child("enabled").path;
  config::warn_deprecated(where, "'" + at.child("enhance.enabled").path +
                                     "' is ignored: the enhance stage always inserts the RIT block; remove it");
  YAML::Node out(YAML::NodeType::Map);
  for (const auto& kv : map)
    if (!kv.first.IsScalar() || kv.first.Scalar() != "enabled") out.force_insert(kv.first, kv.second);
  return out;
}
}  // namespace

config::Schema<TrainOptions> train_schema() {
  return train_schema_with([](config::Schema<TrainOptions>& s) {
    s.section("enhance", &TrainOptions::enhance, enhance_schema(/*with_enabled=*/true), "make a CG-enhanced network");
    s.section("elastic", &TrainOptions::elastic, elastic_training_schema(/*with_enabled=*/true),
              "train an elastic network: every subnet of its space works (sandwich rule, in-place distillation)");
  });
}

config::Schema<TrainOptions> enhance_stage_schema() {
  return train_schema_with([](config::Schema<TrainOptions>& s) {
    s.inline_section(&TrainOptions::enhance, enhance_schema(/*with_enabled=*/false));
    s.moved_block("enhance");  // older configs: `enhance: {enhance: {rit: ...}}`
    s.upgrade(drop_enabled);
  });
}

config::Schema<TrainOptions> elastic_stage_schema() {
  return train_schema_with([](config::Schema<TrainOptions>& s) {
    s.inline_section(&TrainOptions::elastic, elastic_training_schema(/*with_enabled=*/false));
  });
}

namespace {
// One line per optimizer step: the training loss over the global batch (NaN for a skipped step).
void write_loss_curve(const std::filesystem::path& path, const TrainOutcome& outcome) {
  std::string text = "step,loss\n";
  char line[64];
  for (size_t i = 0; i < outcome.loss_curve.size(); ++i) {
    std::snprintf(line, sizeof line, "%zu,%.9g\n", i + 1, outcome.loss_curve[i]);
    text += line;
  }
  write_file_atomic(path, text);
}
}  // namespace

namespace {
// The network a training trains, built before any data is read.
struct NetworkToTrain {
  ModelSource source;                 // the model it starts from
  SRNetwork network{nullptr};
  std::string stage;                  // "backbone", "cg-enhanced" or "elastic"
  std::optional<ElasticSpace> space;  // an elastic training's
};

// The model (a backbone name, a spec or a model file), with the RIT inserted when enhancing and
// made elastic when asked: what the run builds first and what --check builds, so both apply a
// spec's ranges, the RIT's channels and the elastic space's options.
NetworkToTrain network_to_train(const TrainOptions& options) {
  NetworkToTrain t;
  t.source = resolve_model(options.model, options.scale);
  t.network = t.source.network;
  t.stage = "backbone";
  if (options.enhance.enabled) {
    ArchSpec child = t.source.spec;
    child.rit = options.enhance.rit;
    child.rit.enabled = true;
    child.geometry = options.enhance.geometry;
    t.network = inherit(*t.source.network, resolve_spec(child)).network;
    t.stage = "cg-enhanced";
  }
  if (options.elastic.enabled) {
    if (options.quantization_aware.enabled)
      throw Error("train: quantization_aware", "an elastic network's subnets train in float32; remove one of the two");
    if (options.distill.enabled())
      throw Error("train: distill", "an elastic network distils from its own full network; remove 'distill'");
    if (options.elastic.from_scratch) t.network = SRNetwork(t.network->spec());  // the architecture, fresh weights
    ElasticNetwork elastic = make_elastic(*t.network, options.elastic.space);
    t.network = elastic.network;
    t.space.emplace(elastic.space);
    t.stage = "elastic";
  }
  return t;
}
}  // namespace

SRNetwork starting_network(const TrainOptions& options) { return network_to_train(options).network; }

std::string check_train(const TrainOptions& options) {
  const NetworkToTrain t = network_to_train(options);
  return "network  " + spec_summary(t.network->spec()) + ", " + t.stage + ", " +
         std::to_string(inference_parameter_count(*t.network)) + " parameters\n";
}

nlohmann::ordered_json run_train(const TrainOptions& options, const YAML::Node& resolved, RunDir& run_dir) {
  const NetworkToTrain start = network_to_train(options);
  const ModelSource& source = start.source;
  const std::string& stage = start.stage;
  SRNetwork network = start.network;
  // Only what the network reads (its geometry targets are the same channels at HR).
  const Dataset data = open_for_channels(options.data, network->input_channels());
  const std::string name = options.name.empty() ? spec_summary(network->spec()) : options.name;
  spdlog::info("training {} on {} ({} train / {} val frames)", name, data.info().root.string(),
               data.frames(Split::Train).size(), data.frames(Split::Val).size());

  TrainHooks hooks;
  nlohmann::ordered_json extra = {{"name", name}, {"data", data.info().root.string()}};
  const std::optional<ElasticSpace>& space = start.space;
  if (space) {
    hooks = elastic_training_hooks(network, *space, options.elastic, options.loss, options.schedule.steps,
                                   static_cast<uint64_t>(options.seed));
    spdlog::info("{}: elastic over {} layer groups and {} blocks (at least {})", name, space->genes().size(),
                 space->total_blocks(), space->min_blocks());
  } else if (options.distill.enabled()) {
    Model teacher = load_model(options.distill.teacher);
    hooks = distillation_hooks(teacher.network, options.distill.weight, options.loss.image_norm);
    extra["teacher"] = options.distill.teacher;
  }
  if (options.quantization_aware.enabled) {
    const Calibration calibration = calibrate_network(*network, data, options.quantization_aware.calibration);
    network->train();  // calibrate_network left it in eval mode
    hooks = quantization_aware(hooks, network, calibration);
    extra["quantization_aware"] = calibration_json(calibration);
    spdlog::info("{}: quantization-aware: training and validating through simulated int8", name);
  }
  Trainer trainer(network, data, options.schedule, options.loss, {}, hooks);
  std::unique_ptr<distributed::World> world;
  if (options.distributed.enabled()) {
    // What the training depends on, paths aside (they may differ between machines).
    TrainOptions job = options;
    job.data.clear();
    job.distributed = {};
    job.threads = 0;  // compared separately (a warning)
    if (source.kind == ModelSource::Kind::ModelFile) job.model = std::to_string(fnv1a64(read_file(options.model)));
    world = join_run(options.distributed, config::to_yaml(train_schema().emit(job)) + "\n" +
                                              std::to_string(data.frames(Split::Train).size()) + " " +
                                              std::to_string(data.frames(Split::Val).size()));
    trainer.set_data_parallel(world.get());
  }
  trainer.set_resume_force(options.force_resume);
  const TrainOutcome outcome = trainer.run(run_dir.file("checkpoint.pt"), options.resume);
  if (world && !world->coordinator()) {
    // Rank 0 writes the model files; this rank only reports its part.
    nlohmann::ordered_json results;
    results["rank"] = world->rank();
    results["world_size"] = world->size();
    results["training"] = to_json(outcome);
    return results;
  }
  write_loss_curve(run_dir.file("loss_curve.csv"), outcome);

  Provenance provenance;
  provenance.stage = stage;
  provenance.parent = source.kind == ModelSource::Kind::ModelFile ? options.model : "";
  provenance.config = yaml_to_json(resolved);
  provenance.metrics = {{"val_psnr", outcome.best.psnr}, {"val_ssim", outcome.best.ssim}};
  if (space) {
    const auto& lr = data.resolutions().front();
    network->eval();
    extra["elastic"] = elastic_metadata(*space);
    for (Precision p : space->options().precisions) {
      const LatencyTable table =
          measure_latency_table(*network, *space, lr.width, lr.height, options.elastic.latency, p);
      spdlog::info("{}: {} latency table of {} convolution shapes at {}x{}; prediction error on {} subnets: mean "
                   "{:.1f}%, max {:.1f}%", name, enum_name(p), table.conv_ms.size(), lr.width, lr.height,
                   table.error.subnets, table.error.mean_abs_percent, table.error.max_abs_percent);
      extra[latency_table_key(p)] = to_json(table);
    }
  }
  provenance.extra = extra;
  save_model(run_dir.file("model.cgsr"), *network, provenance);
  trainer.save_last_model(run_dir.file("last.cgsr"), provenance);

  nlohmann::ordered_json results;
  results["name"] = name;
  results["stage"] = stage;
  results["spec"] = spec_summary(network->spec());
  results["params"] = inference_parameter_count(*network);
  results["model"] = run_dir.file("model.cgsr").string();
  results["training"] = to_json(outcome);
  if (world) results["world_size"] = world->size();
  spdlog::info("{}: best validation {:.3f} dB / {:.4f} at step {}; {:.1f} patches/s", name, outcome.best.psnr,
               outcome.best.ssim, outcome.best.step, outcome.patches_per_second);
  return results;
}

}  // namespace cgsr
