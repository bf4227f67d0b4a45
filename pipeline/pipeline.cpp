#include "pipeline/pipeline.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>
#include <map>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/timing.h"
#include "core/yaml_json.h"
#include "eval/report.h"
#include "eval/report_page.h"
#include "export/exporter.h"
#include "export/hybrid_export.h"
#include "export/onnx_writer.h"
#include "export/onnxruntime_runner.h"
#include "models/model_file.h"
#include "pipeline/distributed_run.h"
#include "pipeline/eval_stage.h"
#include "pipeline/export_stage.h"
#include "pipeline/prune_stage.h"
#include "pipeline/render_stage.h"
#include "pipeline/search_stage.h"
#include "pipeline/stage_cache.h"
#include "pipeline/train_stage.h"
#include "render_data/dataset.h"
#include "render_data/patch_sampler.h"

namespace fs = std::filesystem;

namespace cgsr {

const std::vector<std::string>& pipeline_stages() {
  static const std::vector<std::string> stages = {"render", "train",    "enhance", "control", "elastic",
                                                  "search", "prune",    "scratch", "controls", "export",
                                                  "eval",   "heldout",  "report"};
  return stages;
}

config::Schema<ScratchOptions> scratch_schema() {
  config::Schema<ScratchOptions> s;
  s.field("enabled", &ScratchOptions::enabled, "train the CG-optimized architecture from scratch (a control)");
  s.field("steps", &ScratchOptions::steps,
          "its steps (0: as many as train, enhance, elastic and the search's fine-tuning together)")
      .range(0, 100000000);
  return s;
}

config::Schema<PipelineOptions> pipeline_schema() {
  config::Schema<PipelineOptions> s;
  s.field("name", &PipelineOptions::name, "run name; the default run directory is runs/<name>");
  s.field("scene", &PipelineOptions::scene, "cgsr render config of the scene to render (or give data)");
  s.field("data", &PipelineOptions::data, "an existing data set directory instead of rendering a scene");
  s.field("baselines", &PipelineOptions::baselines, "classic upscalers in the report (bicubic is always there)")
      .one_of(classic_upscalers().names());
  s.block("train", &PipelineOptions::train, "cgsr train config of the plain backbone (data is filled in)");
  s.block("enhance", &PipelineOptions::enhance,
          "cgsr train config of the CG-enhanced network, its enhance block's rit and geometry at the top (data, model filled in)");
  s.block("elastic", &PipelineOptions::elastic,
          "cgsr train config of the elastic network, its elastic block's keys at the top (data, model filled in)");
  s.block("search", &PipelineOptions::search, "cgsr search config (model, data filled in)");
  s.block("prune", &PipelineOptions::prune, "cgsr prune config (model, data, eval filled in)");
  s.section("scratch", &PipelineOptions::scratch, scratch_schema(),
            "the CG-optimized architecture trained from scratch with the train stage's schedule");
  s.section("controls", &PipelineOptions::controls, controls_schema(),
            "the CG-enhanced network cut to the CG-optimized network's latency, fine-tuned alike");
  s.field("export_formats", &PipelineOptions::export_formats, "formats the final networks are exported to and verified in (onnx, torchscript)");
  s.block("eval", &PipelineOptions::eval, "held-out evaluation options (split, frames; latency_runs: rounds of the report's side-by-side timing)");
  s.field("precisions", &PipelineOptions::precisions,
          "number formats the evaluated networks run in (fp32, bf16, int8), each a row of the report")
      .check([](const auto& v) { return std::find(v.begin(), v.end(), Precision::Fp32) != v.end(); },
             "must include fp32 (the stages' own figures are float32)");
  s.section("calibration", &PipelineOptions::calibration, calibration_schema_fields(),
            "the training frames int8 rows are calibrated on");
  s.section("heldout", &PipelineOptions::heldout, heldout_schema(),
            "scenes not in the training data, on which every model and classic baseline is evaluated");
  s.section("images", &PipelineOptions::images, comparison_schema_fields(),
            "the report's image comparisons: crops and error maps of the test frames with the most geometry edges "
            "and of a frame of each held-out scene");
  s.section("verdict", &PipelineOptions::verdict, verdict_schema(), "what the run must show");
  s.field("from", &PipelineOptions::from, "rerun this stage and every later one").check(
      [](const std::string& v) {
        return v.empty() || std::find(pipeline_stages().begin(), pipeline_stages().end(), v) != pipeline_stages().end();
      },
      "must be one of: " + join(pipeline_stages()));
  s.validate([](const PipelineOptions& o, const config::Cursor& at, const YAML::Node& node) {
    if (o.scene.empty() == o.data.empty())
      at.child("scene").fail(node, "give exactly one of 'scene' (a scene to render) and 'data' (an existing data set)");
  });
  add_run_settings(s);
  return s;
}

namespace {

// A stage's options: the keys of its section plus the keys the pipeline fills in (`filled`),
// parsed with the subcommand's own schema, so errors name the run config's file, line and key.
template <class T>
T parse_stage(const config::Block& block, const config::Schema<T>& schema, const YAML::Node& filled,
              const std::string& stage) {
  const config::Cursor at = block.doc ? block.cursor() : config::Cursor{nullptr, stage};
  const YAML::Node& given = block.node;
  YAML::Node merged(YAML::NodeType::Map);
  if (given && given.IsMap()) {
    for (const auto& kv : given) merged.force_insert(kv.first, kv.second);
  } else if (given && given.IsDefined() && !given.IsNull()) {
    at.fail(given, "expected a map of keys, got " + config::detail::describe(given));
  }
  for (const auto& kv : filled) {
    const std::string key = kv.first.as<std::string>();
    if (given && given.IsMap() && given[key])
      at.child(key).fail(given[key], "is filled in by cgsr run (from the earlier stages); remove it here");
    merged[key] = kv.second;
  }
  T out{};
  schema.parse(merged, out, at);
  return out;
}

struct StageOutcome {
  std::string hash;
  nlohmann::ordered_json summary;
  double seconds = 0;
  bool skipped = false;
};

// Runs the stages in their directories, skipping the finished ones (pipeline/stage_cache.h).
class StageRunner {
 public:
  StageRunner(fs::path root, std::string from, int stages) : root_(std::move(root)), from_(std::move(from)), total_(stages) {}

  fs::path dir(const std::string& stage) const { return root_ / (stage == "render" ? "data" : stage); }

  // `body(run_dir, resume)` does the stage's work and returns its results.
  // The hash is of `resolved`, or of `cache_form` when given (a config whose shape changed but
  // whose meaning did not hashes as before).
  StageOutcome run(const std::string& stage, const YAML::Node& resolved, const std::vector<std::string>& upstream,
                   const std::function<nlohmann::ordered_json(RunDir&, bool)>& body,
                   const YAML::Node& cache_form = YAML::Node()) {
    ++index_;
    forcing_ = forcing_ || stage == from_;
    StageOutcome outcome;
    outcome.hash =
        stage_hash(without_distribution(cache_form.IsDefined() && !cache_form.IsNull() ? cache_form : resolved), upstream);
    const fs::path where = dir(stage);
    if (!forcing_ && stage_is_current(where, outcome.hash)) {
      spdlog::info("[{}/{}] {}: up to date in {}, skipped", index_, total_, stage, where.string());
      outcome.summary = stage_summary(where);
      outcome.skipped = true;
      return outcome;
    }
    // An interrupted stage with the same inputs resumes; anything else starts afresh.
    const fs::path started = where / "stage.started";
    const bool resume = !forcing_ && fs::exists(started) && read_file(started) == outcome.hash;
    if (!resume) {
      // Only ever delete what an earlier cgsr run made: never a user's folder that happens to
      // sit where a stage goes (e.g. --out . next to a folder named data).
      if (fs::exists(where) && !fs::is_empty(where) && !fs::exists(started) && !fs::exists(where / "stage.json"))
        throw Error(where.string(), "exists and was not made by cgsr run; move it or choose another --out");
      fs::remove_all(where);
      fs::create_directories(where);
      write_file_atomic(started, outcome.hash);
    }
    spdlog::info("[{}/{}] {}{} -> {}", index_, total_, stage, resume ? " (resuming)" : "", where.string());
    const auto t0 = std::chrono::steady_clock::now();
    RunDir run_dir(where, /*own_log=*/false);
    run_dir.write_config(resolved);
    outcome.summary = body(run_dir, resume);
    run_dir.write_results(outcome.summary);
    mark_stage_done(where, outcome.hash, outcome.summary);
    outcome.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    spdlog::info("[{}/{}] {}: done in {:.0f} s", index_, total_, stage, outcome.seconds);
    return outcome;
  }

 private:
  fs::path root_;
  std::string from_;
  int total_, index_ = 0;
  bool forcing_ = false;
};

YAML::Node run_settings_node(const PipelineOptions& o) {
  YAML::Node n(YAML::NodeType::Map);
  n["seed"] = o.seed;
  n["threads"] = o.threads;
  return n;
}

const EvalResult* find_result(const std::vector<EvalResult>& results, const std::string& name) {
  for (const auto& r : results)
    if (r.name == name) return &r;
  return nullptr;
}

}  // namespace

namespace {
// One row per network and data set: a later stage's row replaces an earlier one of the same name
// (the eval stage evaluates the CG-optimized network for its other formats; the prune stage's
// float32 row of it is the one the report keeps).
std::vector<EvalResult> without_repeated_rows(std::vector<EvalResult> rows) {
  std::vector<EvalResult> out;
  for (auto& r : rows) {
    const auto same = std::find_if(out.begin(), out.end(),
                                   [&](const EvalResult& o) { return o.name == r.name && o.dataset == r.dataset; });
    if (same != out.end())
      *same = std::move(r);
    else
      out.push_back(std::move(r));
  }
  return out;
}

// ONNX Runtime's latency for every row with an exported file, on the frame the side-by-side
// timing used (the exported file takes the same inputs: lr_color, lr_render_info).
void time_in_onnxruntime(std::vector<EvalResult>& evaluations, const std::map<std::string, fs::path>& onnx_files,
                         const std::vector<Batch>& frames, int runs) {
  if (const std::string why = OnnxRuntimeRunner::unavailable_reason(); !why.empty()) {
    spdlog::warn("report: no ONNX Runtime latency column ({})", why);
    return;
  }
  std::vector<OrtModelJob> jobs;
  std::vector<size_t> rows;
  for (size_t i = 0; i < evaluations.size(); ++i) {
    const auto file = onnx_files.find(evaluations[i].name);
    if (file == onnx_files.end() || !fs::exists(file->second)) continue;
    // The file records its spec; a network of that spec picks its rendering channels from the batch.
    const SRNetwork net(spec_from_yaml(inspect_onnx_file(file->second).metadata_value("cgsr.spec"), file->second.string()));
    const auto inputs = export_inputs(export_signature(net->describe(false)), frames[i].lr_color, net->info_input(frames[i]));
    jobs.push_back({file->second, {{inputs, /*warmup=*/2, runs}}});
    rows.push_back(i);
  }
  if (jobs.empty()) return;
  spdlog::info("timing {} exported models in ONNX Runtime ({} runs each)", jobs.size(), runs);
  const auto results = OnnxRuntimeRunner().run_checked(jobs);
  for (size_t k = 0; k < rows.size(); ++k) {
    evaluations[rows[k]].onnxruntime_latency = summarize_latency(results[k].runs.at(0).times_ms);
  }
}
}  // namespace

namespace {

// The pipeline's stages as named steps over shared state: each step runs (or skips) its stage and
// leaves what later stages read (model files, stage hashes, summaries).
class Pipeline {
 public:
  Pipeline(const PipelineOptions& options, const YAML::Node& resolved, fs::path root)
      : options_(options),
        root_(std::move(root)),
        stages_(root_, options.from,
                static_cast<int>(pipeline_stages().size()) - (options.data.empty() ? 0 : 1) -
                    (options.heldout.scenes.empty() ? 1 : 0) - (options.scratch.enabled ? 0 : 1) -
                    (options.controls.kinds.empty() ? 1 : 0)) {
    parse_stage_options();  // first: a mistake in a stage section is an error at its line
    results_["config"] = yaml_to_json(resolved);
  }

  nlohmann::ordered_json run() {
    const auto t0 = std::chrono::steady_clock::now();
    render();
    train_networks();
    search();
    prune();
    train_scratch();
    cut_controls();
    export_networks();
    evaluate();
    evaluate_heldout();
    report();
    const Verdict verdict = judge();
    write_file_atomic(root_ / "verdict.txt", verdict.text());
    results_["verdict"] = verdict.to_json();
    // The page again, now with the verdict's checks at its top.
    write_report_page(stages_.dir("report"), nlohmann::ordered_json::parse(read_file(stages_.dir("report") / "results.json")),
                      results_["verdict"]);
    results_["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    write_file_atomic(root_ / "results.json", results_.dump(2) + "\n");

    std::printf("\n%s", verdict.text().c_str());
    std::printf("report: %s, verdict: %s, run: %s (%.0f s)\n", (stages_.dir("report") / "report.md").string().c_str(),
                (root_ / "verdict.txt").string().c_str(), root_.string().c_str(), results_["seconds"].get<double>());
    if (!verdict.passed() && options_.verdict.fail_run)
      throw Error(root_.string(), "the verdict failed " + std::to_string(verdict.failed()) + " check(s) (see verdict.txt)",
                  ErrorKind::Internal);
    return results_;
  }

  // What --check does beyond plan(): builds the networks the training stages would train
  // (check_train), so a spec or an enhancement the run would refuse at its train stage, after
  // the render, fails --check. A later stage starts from an earlier one's model file, which does
  // not exist yet: its network is built from the train stage's model instead.
  std::string check_networks() const {
    TrainOptions enhance = enhanced_;
    enhance.model = backbone_.model;
    enhance.scale = backbone_.scale;
    TrainOptions elastic = elastic_;
    elastic.model = backbone_.model;
    elastic.scale = backbone_.scale;
    elastic.enhance = enhanced_.enhance;
    std::string out;
    for (const auto& [stage, options] : {std::pair<const char*, const TrainOptions*>{"train", &backbone_},
                                         {"enhance", &enhance}, {"elastic", &elastic}}) {
      try {
        out += "  " + check_train(*options);
      } catch (const Error& e) {
        throw e.within(stage);
      }
    }
    return out;
  }

  // What --check prints: the constructor parsed every stage's section; this parses every scene
  // config the run names too (the held-out ones are read only when that stage starts, hours in)
  // and says what each stage will do.
  std::string plan() const {
    std::string out;
    const auto line = [&](const std::string& stage, const std::string& what) {
      out += fmt::format("  {:<8} {}\n", stage, what);
    };
    const auto schedule = [](const TrainSchedule& s) {
      return fmt::format("{} steps of batch {} at {}x{} LR patches", s.steps, s.batch_size, s.patch_size, s.patch_size);
    };
    if (rendering_) {
      std::vector<RenderJobOptions> scenes = {scene_};
      if (!scene_.scenes.empty()) {
        scenes.clear();
        for (const auto& job : scene_set_jobs(scene_)) scenes.push_back(job.options);
      }
      int frames = 0;
      for (const auto& s : scenes) frames += s.frames;
      line("render", fmt::format("{}: {} scene(s), {} frames at {}", options_.scene, scenes.size(), frames,
                                 join(scenes.front().resolutions)));
    } else {
      line("data", options_.data);
    }
    line("train", fmt::format("{} x{}, {}", backbone_.model, backbone_.scale, schedule(backbone_.schedule)));
    line("enhance", fmt::format("RIT from {}, {}", enum_name(enhanced_.enhance.rit.source), schedule(enhanced_.schedule)));
    line("control", "the same without the RIT");
    line("elastic", fmt::format("{} subnets per step, {}", elastic_.elastic.sampled + 1, schedule(elastic_.schedule)));
    const std::string budget =
        search_.pick.latency_ms > 0
            ? fmt::format("{:g} ms", search_.pick.latency_ms)
            : fmt::format("{:g} of the latency of {}", search_.pick.latency_fraction,
                          search_.pick.reference.empty()                           ? "the full network"
                          : search_.pick.reference == model_file("train").string() ? "the train stage's network"
                                                                                   : search_.pick.reference);
    line("search", fmt::format("{}, population {} over {} generations{}; the pick within {}, fine-tuned {}",
                               search_.search.strategy.type, search_.search.population, search_.search.generations,
                               search_.baseline.empty() ? "" : ", and " + search_.baseline + " search as many", budget,
                               schedule(search_.final.schedule)));
    line("prune", fmt::format("{} patterns of the front, fine-tuning {}", prune_.pool.latency_factors.size(),
                              schedule(prune_.finetune.schedule)));
    if (options_.scratch.enabled) line("scratch", fmt::format("the pick's architecture, {} steps", scratch_steps()));
    if (!options_.controls.kinds.empty()) {
      std::vector<std::string> kinds;
      for (auto k : options_.controls.kinds) kinds.push_back(control_label(k));
      std::vector<std::string> factors;
      for (double f : options_.controls.latency_factors) factors.push_back(fmt::format("{:g}x", f));
      line("controls", join(kinds) + " at " + join(factors) + " the CG-optimized network's latency, " +
                           schedule(search_.final.schedule));
    }
    std::vector<std::string> formats;
    for (auto f : options_.export_formats) formats.push_back(enum_name(f));
    line("export", join(formats));
    line("eval", "the " + eval_.split + " split" + (eval_.frames.empty() ? "" : ", frames " + eval_.frames));
    for (const auto& config : options_.heldout.scenes) heldout_scene(config);
    if (!options_.heldout.scenes.empty())
      line("heldout", fmt::format("{} scene(s), {} frames each: {}", options_.heldout.scenes.size(),
                                  options_.heldout.frames, join(options_.heldout.scenes)));
    line("report", (stages_.dir("report") / "report.md").string());
    return out;
  }

 private:
  // No references into `results_`: an ordered_json object is a vector, and inserting moves it.
  void record(const std::string& stage, const StageOutcome& o) {
    results_["stages"][stage] = o.summary;
    results_["stage_seconds"][stage] = o.skipped ? nlohmann::ordered_json("cached") : nlohmann::ordered_json(o.seconds);
  }

  fs::path model_file(const std::string& stage) const {
    return stages_.dir(stage) / (stage == "prune" ? "pruned.cgsr" : "model.cgsr");
  }

  // Every stage's options first, so that a mistake anywhere in the config stops the run before
  // its first stage rather than after an hour of training.
  void parse_stage_options() {
    rendering_ = options_.data.empty();
    data_path_ = rendering_ ? stages_.dir("render").string() : options_.data;
    if (rendering_) {
      scene_ = config::parse_document(config::Document::load_file(options_.scene), render_schema());
      scene_.seed = options_.seed;
      scene_.threads = options_.threads;
    }
    YAML::Node with_data = run_settings_node(options_);
    with_data["data"] = data_path_;
    backbone_ = parse_stage(options_.train, train_schema(), with_data, "train");
    YAML::Node enhance_filled = YAML::Clone(with_data);
    enhance_filled["model"] = model_file("train").string();
    enhanced_ = parse_stage(options_.enhance, enhance_stage_schema(), enhance_filled, "enhance");
    enhanced_.enhance.enabled = true;
    control_ = enhanced_;  // same start, schedule, loss and seed; no rendering information
    control_.enhance.enabled = false;
    YAML::Node elastic_filled = YAML::Clone(with_data);
    elastic_filled["model"] = model_file("enhance").string();
    elastic_ = parse_stage(options_.elastic, elastic_stage_schema(), elastic_filled, "elastic");
    elastic_.elastic.enabled = true;
    YAML::Node search_filled = YAML::Clone(with_data);
    search_filled["model"] = model_file("elastic").string();
    search_ = parse_stage(options_.search, search_command_schema(), search_filled, "search");
    // The pick's budget is a fraction of what the verdict's latency check divides by: the backbone.
    if (search_.pick.reference.empty() && search_.pick.measure_runs > 0)
      search_.pick.reference = model_file("train").string();
    // From scratch: the pick's architecture (the search writes it) with the train stage's schedule.
    scratch_ = backbone_;
    scratch_.model = (stages_.dir("search") / "pick_spec.yaml").string();
    scratch_.schedule.steps = scratch_steps();
    eval_ = parse_stage(options_.eval, eval_schema_fields(), YAML::Node(YAML::NodeType::Map), "eval");
    // A distributed stage's other ranks are `cgsr search` / `cgsr train` processes (docs/distributed.md).
    for (const auto& [stage, rank] : {std::pair<const char*, int>{"train", backbone_.distributed.rank},
                                      {"enhance", enhanced_.distributed.rank}, {"elastic", elastic_.distributed.rank}})
      if (rank != 0)
        throw Error(std::string(stage) + ".distributed.rank",
                    "cgsr run is rank 0 of a distributed stage; start the other ranks with cgsr train "
                    "(docs/distributed.md)");
    // The stages that evaluate (prune, eval, heldout) leave latency out: the report stage times
    // every model side by side, which is the only timing that compares.
    stage_eval_ = eval_;
    stage_eval_.latency_runs = 0;
    YAML::Node prune_filled = YAML::Clone(with_data);
    prune_filled["model"] = model_file("elastic").string();
    prune_filled["search"] = (stages_.dir("search") / "results.json").string();
    prune_filled["eval"] = eval_schema_fields().emit(stage_eval_);
    prune_ = parse_stage(options_.prune, prune_command_schema(), prune_filled, "prune");
  }

  void render() {
    if (rendering_) {
      const auto o = stages_.run("render", render_schema().emit(scene_), {}, [&](RunDir& dir, bool) {
        return run_render(scene_, dir);
      });
      record("render", o);
      data_hash_ = o.hash;
    } else {
      data_hash_ = stage_hash(YAML::Node(fs::absolute(options_.data).string()), {});
    }
    data_ = std::make_unique<Dataset>(Dataset::open(data_path_));
  }

  // The plain backbone; the CG-enhanced network (backbone + RIT, + geometry head) trained on from
  // it with the joint loss; and the control, the backbone trained on as long without the RIT.
  void train_networks() {
    trained_ = train_with(train_schema(), "train", backbone_, {data_hash_});
    enhanced_stage_ = train_with(train_schema(), "enhance", enhanced_, {data_hash_, trained_.hash});
    control_.name = trained_.summary.at("name").get<std::string>() + " (control)";
    control_stage_ = train_with(train_schema(), "control", control_, {data_hash_, trained_.hash});
    if (elastic_.name.empty()) elastic_.name = "elastic " + enhanced_stage_.summary.at("name").get<std::string>();
    elastic_stage_ = train_with(elastic_stage_schema(), "elastic", elastic_, {data_hash_, enhanced_stage_.hash});
  }

  // Steps of the scratch control: what the pipeline gave the CG-optimized network's weights (an
  // elastic network trained from scratch owes the train and enhance stages nothing).
  int scratch_steps() const {
    if (options_.scratch.steps > 0) return options_.scratch.steps;
    const int before = elastic_.elastic.from_scratch ? 0 : backbone_.schedule.steps + enhanced_.schedule.steps;
    return before + elastic_.schedule.steps + search_.final.schedule.steps;
  }

  // A training stage: `schema` emits the config it is recorded and hashed with.
  StageOutcome train_with(const config::Schema<TrainOptions>& schema, const std::string& stage, TrainOptions& o,
                          const std::vector<std::string>& upstream) {
    const auto outcome = stages_.run(stage, schema.emit(o), upstream, [&](RunDir& dir, bool resume) {
      o.resume = resume;
      return run_train(o, schema.emit(o), dir);
    });
    record(stage, outcome);
    return outcome;
  }

  // The CG-optimized network's architecture trained from random weights.
  void train_scratch() {
    if (!options_.scratch.enabled) return;
    scratch_.name = roles_.input.name + " (scratch)";
    scratched_ = train_with(train_schema(), "scratch", scratch_, {data_hash_, searched_.hash});
  }

  // The CG-enhanced network cut to the CG-optimized network's latency, fine-tuned alike.
  void cut_controls() {
    if (options_.controls.kinds.empty()) return;
    ControlsJob job;
    job.seed = options_.seed;
    job.threads = options_.threads;
    job.options = options_.controls;
    job.enhanced = model_file("enhance").string();
    job.final_model = model_file("search").string();
    job.data = data_path_;
    job.schedule = search_.final.schedule;
    job.loss = search_.final.loss;
    job.distill = search_.final.distill;
    YAML::Node config = controls_schema().emit(options_.controls);
    config["schedule"] = schedule_schema().emit(job.schedule);
    config["loss"] = loss_schema().emit(job.loss);
    config["distill"] = job.distill;
    controlled_ = stages_.run("controls", config, {data_hash_, enhanced_stage_.hash, searched_.hash},
                              [&](RunDir& dir, bool resume) { return run_controls(job, dir, resume); });
    record("controls", controlled_);
    for (const auto& c : controlled_.summary.at("controls"))
      controls_.push_back({c.at("name").get<std::string>(), c.at("file").get<std::string>()});
  }

  // CG-enhanced -> CG-optimized.
  void search() {
    const YAML::Node resolved = search_command_schema().emit(search_);
    searched_ = stages_.run("search", resolved, {data_hash_, elastic_stage_.hash}, [&](RunDir& dir, bool resume) {
      search_.resume = resume;
      return run_search_command(search_, search_command_schema().emit(search_), dir);
    });
    record("search", searched_);
  }

  // Hybrid pruning of the CG-optimized network and its baselines (evaluated with the run's eval options).
  void prune() {
    pruned_ = stages_.run("prune", prune_command_schema().emit(prune_), {data_hash_, elastic_stage_.hash, searched_.hash},
                          [&](RunDir& dir, bool resume) {
                            prune_.resume = resume;
                            return run_prune(prune_, prune_command_schema().emit(prune_), dir);
                          });
    record("prune", pruned_);
    roles_ = prune_roles_from_json(pruned_.summary.at("roles"), (stages_.dir("prune") / "results.json").string());
  }

  // The CG-optimized and pruned networks go out in every format, verified in the other runtimes;
  // the others as ONNX only, for the report's ONNX Runtime latency column. Each file is named
  // after its role; the hybrid model goes out as its deployment directory (a file per pattern,
  // the selector, the manifest).
  void export_networks() {
    const Resolution lr = data_->info().resolutions.front();
    const fs::path pruned_file = model_file("prune");
    std::vector<std::pair<fs::path, std::string>> to_export = {
        {model_file("train"), "backbone"}, {model_file("enhance"), "cg_enhanced"}, {model_file("elastic"), "elastic"},
        {model_file("search"), "cg_optimized"}};
    if (options_.scratch.enabled) to_export.emplace_back(model_file("scratch"), "scratch");
    for (const auto& c : controls_) to_export.emplace_back(c.file, "control_" + c.file.stem().string());
    to_export.emplace_back(pruned_file, "pruned");
    std::vector<ExportCommandOptions> exports;
    YAML::Node export_config(YAML::NodeType::Sequence);
    for (const auto& [model, stem] : to_export) {
      const bool deployed = stem == "cg_optimized" || stem == "pruned";
      for (const auto& format : options_.export_formats) {
        if (!deployed && format != ExportFormat::Onnx) continue;
        ExportCommandOptions e;
        e.seed = options_.seed;
        e.threads = options_.threads;
        e.model = model.string();
        e.format = format;
        e.input = lr.name();
        e.verify = true;
        const bool onnx = format == ExportFormat::Onnx;
        e.out = (stages_.dir("export") / (model == pruned_file ? stem + (onnx ? "" : "_torchscript")
                                                               : stem + (onnx ? ".onnx" : ".pt")))
                    .string();
        // The hybrid's pattern 0 is its static network.
        if (onnx)
          onnx_of_file_[model.string()] =
              model == pruned_file ? fs::path(e.out) / pattern_file_name(0, format) : fs::path(e.out);
        exports.push_back(e);
        export_config.push_back(export_schema().emit(e));
        if (!onnx || model == pruned_file || !in_precision(Precision::Int8)) continue;
        // The same network quantized, for the int8 rows' ONNX Runtime column.
        e.precision = Precision::Int8;
        e.data = data_path_;
        e.calibration = options_.calibration;
        e.out = (stages_.dir("export") / (stem + "_int8.onnx")).string();
        int8_onnx_of_file_[model.string()] = e.out;
        exports.push_back(e);
        export_config.push_back(export_schema().emit(e));
      }
    }
    exported_ = stages_.run("export", export_config,
                            {trained_.hash, enhanced_stage_.hash, elastic_stage_.hash, searched_.hash, pruned_.hash,
                             scratched_.hash, controlled_.hash},
                            [&](RunDir&, bool) {
                              nlohmann::ordered_json j = nlohmann::ordered_json::array();
                              for (const auto& e : exports) j.push_back(run_export(e));
                              return nlohmann::ordered_json{{"exports", j}};
                            });
    record("export", exported_);
  }

  // The classic baselines, the backbone, the control and the CG-enhanced network (prune
  // evaluated the rest).
  void evaluate() {
    EvalCommandOptions evaluation;
    evaluation.seed = options_.seed;
    evaluation.threads = options_.threads;
    evaluation.data = data_path_;
    evaluation.scale = backbone_.scale;
    evaluation.eval = stage_eval_;
    evaluation.models = classic_models();
    for (const std::string stage : {"train", "control", "enhance", "elastic"})
      evaluation.models.push_back(model_file(stage).string());
    for (const auto& extra : control_models()) evaluation.models.push_back(extra.file.string());
    evaluation.precisions = options_.precisions;
    evaluation.calibration = options_.calibration;
    std::vector<std::string> upstream = {data_hash_,          trained_.hash,   control_stage_.hash, enhanced_stage_.hash,
                                         elastic_stage_.hash, scratched_.hash, controlled_.hash};
    // The CG-optimized network's float32 row is the prune stage's; here its other formats.
    if (options_.precisions.size() > 1) {
      evaluation.models.push_back(model_file("search").string());
      upstream.push_back(searched_.hash);
    }
    evaluated_ = stages_.run("eval", eval_schema().emit(evaluation), upstream,
                             [&](RunDir& dir, bool) { return run_eval(evaluation, &dir); });
    record("eval", evaluated_);
  }

  // Every model of the run and the classic baselines on scenes it never trained on.
  void evaluate_heldout() {
    if (options_.heldout.scenes.empty()) return;
    HeldoutJob job;
    job.models = classic_models();
    for (const std::string stage : {"train", "control", "enhance", "search"}) job.models.push_back(model_file(stage).string());
    job.models.push_back(model_file("prune").string());
    for (const auto& extra : control_models()) job.models.push_back(extra.file.string());
    job.scale = backbone_.scale;
    job.lr = data_->info().resolutions.front();
    job.training_scene = data_->info().name;
    job.eval = stage_eval_;
    job.seed = options_.seed;
    job.threads = options_.threads;
    YAML::Node config = heldout_schema().emit(options_.heldout);
    config["models"] = job.models;
    heldout_ = stages_.run(
        "heldout", config,
        {trained_.hash, control_stage_.hash, enhanced_stage_.hash, searched_.hash, pruned_.hash, scratched_.hash,
         controlled_.hash},
        [&](RunDir& dir, bool) { return run_heldout(options_.heldout, job, dir.path()); });
    record("heldout", heldout_);
  }

  // The scratch network and the controls of equal latency, with their display names.
  std::vector<PrunedModel> control_models() const {
    std::vector<PrunedModel> out;
    if (options_.scratch.enabled) out.push_back({scratch_.name, model_file("scratch")});
    out.insert(out.end(), controls_.begin(), controls_.end());
    return out;
  }

  bool in_precision(Precision p) const {
    return std::find(options_.precisions.begin(), options_.precisions.end(), p) != options_.precisions.end();
  }

  std::vector<std::string> classic_models() const {
    std::vector<std::string> models = {"bicubic"};
    for (const auto& b : options_.baselines)
      if (b != "bicubic") models.push_back(b);
    return models;
  }

  // One table and plot of every model. The stages timed their models minutes or hours apart,
  // under whatever else the machine was doing then; the report times them again side by side, in
  // interleaved rounds over the evaluated frames in turn, so that their latencies compare. The
  // held-out scenes' rows join untimed.
  void report() {
    const std::vector<std::string> runs = {(stages_.dir("eval") / "results.json").string(),
                                           (stages_.dir("prune") / "results.json").string()};
    const std::vector<std::string> heldout_runs = heldout_result_files(heldout_.summary);
    std::vector<std::string> report_runs = runs;
    report_runs.insert(report_runs.end(), heldout_runs.begin(), heldout_runs.end());
    std::vector<std::string> upstream = {evaluated_.hash, pruned_.hash, exported_.hash};
    if (!heldout_runs.empty()) upstream.push_back(heldout_.hash);
    YAML::Node config(YAML::NodeType::Map);
    config["runs"] = report_runs;
    config["images"] = comparison_schema_fields().emit(options_.images);
    const auto reported = stages_.run("report", config, upstream, [&](RunDir& dir, bool) {
      std::vector<EvalResult> evaluations = without_repeated_rows(collect_evaluations(runs));
      const auto upscalers = report_upscalers(evaluations);
      if (eval_.latency_runs > 0) time_side_by_side(evaluations, upscalers);
      const std::vector<EvalResult> unseen = collect_evaluations(heldout_runs);
      const auto comparisons = compare_images(evaluations, unseen, upscalers, dir.path() / "images");
      evaluations.insert(evaluations.end(), unseen.begin(), unseen.end());
      return write_report(evaluations, dir, heldout_scenes(heldout_.summary), report_roles(), comparisons);
    });
    record("report", reported);
    if (reported.skipped) std::printf("%s", read_file(stages_.dir("report") / "report.md").c_str());
  }

  // Which rows are final networks and controls, and which control belongs to which network.
  ReportRoles report_roles() const {
    ReportRoles r;
    const std::string enhanced = enhanced_stage_.summary.at("name").get<std::string>();
    r.finals = {roles_.input.name, roles_.hybrid.name};
    r.controls = {control_.name};
    r.pairs = {{enhanced, control_.name}};
    if (options_.scratch.enabled) {
      r.controls.push_back(scratch_.name);
      r.pairs.emplace_back(roles_.input.name, scratch_.name);
    }
    // Each kind's cuts as one curve, labelled by kind and latency factor; the final network is
    // joined to its equal-latency cut (the curve shows the others).
    if (controlled_.summary.contains("controls"))
      for (const auto& c : controlled_.summary.at("controls")) {
        const auto kind = enum_from_name<ControlKind>(c.at("kind").get<std::string>());
        const std::string name = c.at("name").get<std::string>(), label = control_label(kind);
        const std::string curve_name = label + " control";
        const double factor = c.at("latency_factor").get<double>();
        auto curve = std::find_if(r.curves.begin(), r.curves.end(), [&](const auto& x) { return x.name == curve_name; });
        if (curve == r.curves.end()) curve = r.curves.insert(r.curves.end(), ReportCurve{curve_name, {}});
        curve->points.emplace_back(name, fmt::format("{} {:g}x", label, factor));
        r.controls.push_back(name);
        if (factor == 1.0) r.pairs.emplace_back(roles_.input.name, name);
      }
    return r;
  }

  // The upscaler of every row, in order: classic ones by name, networks from their files.
  std::vector<std::unique_ptr<Upscaler>> report_upscalers(const std::vector<EvalResult>& evaluations) const {
    const auto files = model_files();
    std::vector<std::unique_ptr<Upscaler>> upscalers;
    for (const auto& e : evaluations) {
      if (e.precision != Precision::Fp32) {
        const std::string network = network_of_row(e.name, e.precision);
        const auto base = make_upscaler(files.at(network).string(), network, backbone_.scale);
        upscalers.push_back(upscaler_in_precision(*base, e.precision, *data_, options_.calibration));
        continue;
      }
      const auto file = files.find(e.name);
      if (e.name == roles_.static_network.name)
        upscalers.push_back(std::make_unique<NetworkUpscaler>(e.name, load_model(model_file("prune")).network));
      else
        upscalers.push_back(
            make_upscaler(file == files.end() ? e.name : file->second.string(), e.name, backbone_.scale));
    }
    return upscalers;
  }

  // Crops and error maps of every network: on the test frames with the most geometry edges and
  // on the frame with the most of each held-out scene.
  std::vector<ComparisonImage> compare_images(const std::vector<EvalResult>& own, const std::vector<EvalResult>& unseen,
                                              const std::vector<std::unique_ptr<Upscaler>>& upscalers,
                                              const fs::path& dir) const {
    std::vector<ComparisonImage> out;
    if (options_.images.frames == 0) return out;
    std::vector<Upscaler*> networks;
    for (size_t i = 0; i < own.size(); ++i)
      if (!classic_upscalers().contains(own[i].name)) networks.push_back(upscalers[i].get());
    const EvalResult* bicubic = find_result(own, "bicubic");
    if (!bicubic) return out;
    for (int frame : frames_with_most_edges(*bicubic, options_.images.frames)) {
      spdlog::info("report: image comparison of {} frame {}", data_->info().name, frame);
      out.push_back(compare_frame(networks, *data_, frame, backbone_.scale, options_.images, dir));
    }
    const auto scenes = heldout_scenes(heldout_.summary);
    for (size_t k = 0; k < scenes.size(); ++k) {
      const auto row = std::find_if(unseen.begin(), unseen.end(),
                                    [&](const EvalResult& e) { return e.dataset == scenes[k] && e.name == "bicubic"; });
      if (row == unseen.end()) continue;
      const Dataset level = Dataset::open(heldout_.summary.at("scenes").at(k).at("data").get<std::string>());
      for (int frame : frames_with_most_edges(*row, 1)) {
        spdlog::info("report: image comparison of {} frame {}", scenes[k], frame);
        out.push_back(compare_frame(networks, level, frame, backbone_.scale, options_.images, dir));
      }
    }
    return out;
  }

  // Every row's model file by its display name (the static network is read from the hybrid
  // model's file as a plain model).
  std::map<std::string, fs::path> model_files() const {
    std::map<std::string, fs::path> files = {{trained_.summary.at("name").get<std::string>(), model_file("train")},
                                             {control_.name, model_file("control")},
                                             {enhanced_stage_.summary.at("name").get<std::string>(), model_file("enhance")},
                                             {roles_.input.name, model_file("search")},
                                             {roles_.hybrid.name, model_file("prune")},
                                             {roles_.static_network.name, model_file("prune")}};
    files[elastic_.name] = model_file("elastic");
    for (const auto& extra : control_models()) files[extra.name] = extra.file;
    return files;
  }

  void time_side_by_side(std::vector<EvalResult>& evaluations,
                         const std::vector<std::unique_ptr<Upscaler>>& upscalers) const {
    const auto files = model_files();
    std::map<std::string, fs::path> onnx_files;  // each row's exported ONNX file
    for (const auto& [name, file] : files) {
      const auto onnx = onnx_of_file_.find(file.string());
      if (onnx != onnx_of_file_.end() && name != roles_.hybrid.name) onnx_files[name] = onnx->second;
      const auto int8 = int8_onnx_of_file_.find(file.string());
      if (int8 != int8_onnx_of_file_.end()) onnx_files[precision_row_name(name, Precision::Int8)] = int8->second;
    }
    std::vector<TimingSequence> sequences;  // per model, test frames timed in turn
    std::vector<Batch> frames;              // per model, the first of them
    std::vector<std::function<void()>> timed;
    // The frames the rows were evaluated on (of a scene set, e.g. one scene's), not the whole split:
    // a hybrid's latency follows the patterns its frames choose.
    const std::vector<int> test_frames = evaluation_frames(*data_, eval_);
    for (const auto& u : upscalers) {
      sequences.push_back(timing_sequence(*data_, test_frames, backbone_.scale, *u, eval_.latency_runs));
      frames.push_back(sequences.back().frames.front());
    }
    for (size_t i = 0; i < upscalers.size(); ++i)
      timed.push_back([&, i, next = size_t{0}]() mutable {
        sequences[i].run(*upscalers[i], next++ % sequences[i].size());
      });
    spdlog::info("timing {} models side by side ({} interleaved rounds over {} test frames)", timed.size(),
                 eval_.latency_runs, sequences.front().size());
    const auto latency = measure_latency_interleaved(timed, /*warmup=*/2, eval_.latency_runs);
    for (size_t i = 0; i < evaluations.size(); ++i) evaluations[i].latency = latency[i];
    time_in_onnxruntime(evaluations, onnx_files, frames, eval_.latency_runs);
  }

  // The verdict on the report's rows: the run's own rows are those of its data set (the
  // held-out scenes' rows share their names).
  Verdict judge() {
    for (auto& e : collect_evaluations({(stages_.dir("report") / "results.json").string()}))
      (e.dataset == data_->info().name ? own_ : unseen_).push_back(std::move(e));
    PipelineResults roles;
    roles.bicubic = find_result(own_, "bicubic");
    roles.backbone = find_result(own_, trained_.summary.at("name").get<std::string>());
    roles.control = find_result(own_, control_.name);
    roles.cg_enhanced = find_result(own_, enhanced_stage_.summary.at("name").get<std::string>());
    roles.cg_optimized = find_result(own_, roles_.input.name);
    roles.pruned = find_result(own_, roles_.hybrid.name);
    roles.pruned_static = find_result(own_, roles_.static_network.name);
    roles.elastic = find_result(own_, elastic_.name);
    if (options_.scratch.enabled) roles.scratch = find_result(own_, scratch_.name);
    for (const auto& c : controls_)
      if (const auto* r = find_result(own_, c.name)) {
        roles.controls.push_back(r);
        if (c.file.stem() == enum_name(ControlKind::Magnitude)) roles.magnitude = r;
      }
    const auto& searches = searched_.summary.at("searches");
    for (const auto& [strategy, stats] : searches.items())
      roles.searches.push_back({strategy, stats.at("evaluations").get<int>(), stats.at("hypervolume").get<double>()});
    if (!roles.bicubic || !roles.backbone || !roles.control || !roles.cg_enhanced || !roles.cg_optimized || !roles.pruned)
      throw Error(root_.string(), "the evaluations miss a model of the pipeline (searched: " + roles_.input.name + ")",
                  ErrorKind::Internal);
    for (const auto& scene : heldout_scenes(heldout_.summary)) {
      const auto row = [&](const std::string& name) -> const EvalResult* {
        for (const auto& e : unseen_)
          if (e.dataset == scene && e.name == name) return &e;
        return nullptr;
      };
      HeldoutScene h{scene, row("bicubic"), {}};
      for (const EvalResult* n : roles.networks())
        if (const EvalResult* r = row(n->name)) h.networks.push_back(r);
      if (roles.cg_optimized) h.cg_optimized = row(roles.cg_optimized->name);
      if (roles.scratch) h.scratch = row(roles.scratch->name);
      roles.heldout.push_back(std::move(h));
    }
    return judge_pipeline(roles, options_.verdict);
  }

  const PipelineOptions& options_;
  fs::path root_;
  StageRunner stages_;
  nlohmann::ordered_json results_;

  // Options of every stage, parsed up front.
  bool rendering_ = false;
  std::string data_path_;
  RenderOptions scene_;
  TrainOptions backbone_, enhanced_, control_, elastic_, scratch_;
  SearchCommandOptions search_;
  PruneCommandOptions prune_;
  EvalOptions eval_, stage_eval_;

  // What the stages leave for later ones.
  std::string data_hash_;
  std::unique_ptr<Dataset> data_;
  StageOutcome trained_, enhanced_stage_, control_stage_, elastic_stage_, searched_, pruned_, scratched_, controlled_,
      exported_, evaluated_, heldout_;
  PruneRoles roles_;
  std::vector<PrunedModel> controls_;  // the controls of equal latency
  std::map<std::string, fs::path> onnx_of_file_;       // model file -> its exported ONNX file
  std::map<std::string, fs::path> int8_onnx_of_file_;  // model file -> its QDQ export (int8 rows)
  std::vector<EvalResult> own_, unseen_;          // the report's rows: the run's data set, held-out scenes
};

}  // namespace

nlohmann::ordered_json run_pipeline(const PipelineOptions& options, const YAML::Node& resolved, const fs::path& root) {
  return Pipeline(options, resolved, root).run();
}

std::string check_pipeline(const PipelineOptions& options, const fs::path& dir) {
  const Pipeline pipeline(options, YAML::Node(), dir);
  return dir.string() + ":\n" + pipeline.plan() + pipeline.check_networks();
}

}  // namespace cgsr
