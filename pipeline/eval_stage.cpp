#include "pipeline/eval_stage.h"

#include <spdlog/spdlog.h>

#include <cstdio>

#include "core/atomic_file.h"
#include "core/metrics.h"
#include "eval/frame_plot.h"
#include "eval/report.h"
#include "eval/report_page.h"
#include "models/model_file.h"
#include "pruning/hybrid_upscaler.h"
#include "render_data/dataset.h"

namespace cgsr {

config::Schema<EvalCommandOptions> eval_schema() {
  config::Schema<EvalCommandOptions> s;
  s.field("data", &EvalCommandOptions::data, "data set directory").required();
  s.field("scene", &EvalCommandOptions::scene, "evaluate one scene of a multi-scene data set (default: all)");
  s.omit_when("scene", [](const EvalCommandOptions& o) { return o.scene.empty(); });  // `cgsr run`'s eval hash as before
  s.field("models", &EvalCommandOptions::models,
          "model files and classic upscalers (" + join(classic_upscalers().names()) +
              ", or 'classic' for all that read the colour alone)")
      .check([](const auto& v) { return !v.empty(); }, "needs at least one model or upscaler");
  s.field("names", &EvalCommandOptions::names, "display names, in the order of models");
  s.field("scale", &EvalCommandOptions::scale, "scale of the classic upscalers").range(2, 4);
  s.section("eval", &EvalCommandOptions::eval, eval_schema_fields(), "what and how to evaluate");
  s.section("images", &EvalCommandOptions::images, comparison_schema_fields(),
            "crops and error maps of the evaluated frames with the most geometry edges, into images/");
  s.omit_when("images", [](const EvalCommandOptions& o) { return o.images.frames == 0; });  // stage hashes as before
  s.field("precisions", &EvalCommandOptions::precisions,
          "number formats each network runs in on the fused engine: fp32, bf16, int8")
      .check([](const auto& v) { return !v.empty(); }, "needs at least one precision");
  s.section("calibration", &EvalCommandOptions::calibration, calibration_schema_fields(),
            "the frames int8 activation ranges are measured on");
  const auto only_fp32 = [](const EvalCommandOptions& o) { return o.precisions == std::vector{Precision::Fp32}; };
  s.omit_when("precisions", only_fp32);
  s.omit_when("calibration", only_fp32);
  s.validate([](const EvalCommandOptions& o, const config::Cursor& at, const YAML::Node& node) {
    if (!o.names.empty() && o.names.size() != o.models.size())
      at.child("names").fail(node["names"] ? node["names"] : node, "needs one name per model");
  });
  add_run_settings(s);
  return s;
}

std::unique_ptr<Upscaler> make_upscaler(const std::string& entry, const std::string& name, int scale) {
  if (classic_upscalers().contains(entry)) return classic_upscalers().get(entry)(scale);
  if (!std::filesystem::exists(entry))
    throw Error(entry, "neither a model file nor a classic upscaler (" + join(classic_upscalers().names()) + ")");
  Model model = load_model(entry);
  if (is_hybrid_model(model.provenance)) return make_hybrid_upscaler(entry, name);  // per-frame dynamic pruning
  std::string display = name;
  if (display.empty()) display = model.provenance.extra.value("name", std::filesystem::path(entry).stem().string());
  return std::make_unique<NetworkUpscaler>(display, model.network);
}

std::unique_ptr<Upscaler> upscaler_in_precision(const Upscaler& upscaler, Precision precision, const Dataset& data,
                                                const CalibrationOptions& calibration) {
  if (const auto* network = dynamic_cast<const NetworkUpscaler*>(&upscaler))
    return network_in_precision(*network, precision, data, calibration);
  if (const auto* hybrid = dynamic_cast<const HybridUpscaler*>(&upscaler))
    return hybrid_in_precision(*hybrid, precision, data, calibration);
  return nullptr;
}

namespace {
// The data set loading only the channels the upscalers read, plus motion vectors for the
// temporal error and edges for the PSNR on geometry edges (evaluate() reads them at HR):
// decoding a 1080p frame's other G-buffers would cost more than the metrics.
Dataset open_for(const std::string& path, const std::vector<std::unique_ptr<Upscaler>>& upscalers, bool temporal) {
  std::vector<RenderChannel> needed;
  for (const auto& u : upscalers)
    for (auto c : u->channels()) needed.push_back(c);
  if (temporal) needed.push_back(RenderChannel::Motion);
  return open_for_channels(path, needed);
}

// Every network and hybrid among `upscalers` in each of `precisions`, next to each other
// ("name int8"); classic upscalers once.
std::vector<std::unique_ptr<Upscaler>> in_precisions(std::vector<std::unique_ptr<Upscaler>> upscalers,
                                                     const std::vector<Precision>& precisions, const Dataset& data,
                                                     const CalibrationOptions& calibration) {
  if (precisions == std::vector{Precision::Fp32}) return upscalers;
  std::vector<std::unique_ptr<Upscaler>> out;
  for (auto& u : upscalers) {
    std::vector<std::unique_ptr<Upscaler>> formats;
    for (Precision p : precisions)
      if (auto in = upscaler_in_precision(*u, p, data, calibration)) formats.push_back(std::move(in));
    if (formats.empty()) formats.push_back(std::move(u));
    for (auto& f : formats) out.push_back(std::move(f));
  }
  return out;
}

// Comparisons of the `options.frames` frames of `evaluated` with the most geometry edges, with
// the networks among `upscalers` (the classic ones are always drawn).
std::vector<ComparisonImage> compare_frames(const std::vector<std::unique_ptr<Upscaler>>& upscalers, const Dataset& data,
                                            const EvalResult& evaluated, const ComparisonOptions& options,
                                            const std::filesystem::path& dir) {
  std::vector<Upscaler*> networks;
  for (const auto& u : upscalers)
    // Classic upscalers have no cost and nearest, bicubic and fsr are drawn anyway; the BSP border
    // upsampler is drawn like a network (it is what the comparison is for where it runs).
    if (u->cost(1, 1) || u->reads_bsp_border()) networks.push_back(u.get());
  std::vector<ComparisonImage> out;
  for (int frame : frames_with_most_edges(evaluated, options.frames)) {
    spdlog::info("image comparison of {} frame {}", data.info().name, frame);
    out.push_back(compare_frame(networks, data, frame, upscalers.front()->scale(), options, dir));
  }
  return out;
}
}  // namespace

nlohmann::ordered_json run_eval(const EvalCommandOptions& options, RunDir* run_dir) {
  std::vector<std::pair<std::string, std::string>> entries;  // (model entry, display name)
  std::vector<bool> from_classic;                             // listed by 'classic', not by name
  for (size_t i = 0; i < options.models.size(); ++i) {
    const std::string name = options.names.empty() ? "" : options.names[i];
    if (options.models[i] == "classic") {
      for (const auto& c : classic_upscalers().names()) {
        // The single-frame filters: the temporal ones (history, bicubic_at_jitter) are named on
        // their own, for jittered data sets with motion.
        if (classic_upscalers().get(c)(options.scale)->reads_jitter()) continue;
        entries.emplace_back(c, "");
        from_classic.push_back(true);
      }
    } else {
      entries.emplace_back(options.models[i], name);
      from_classic.push_back(false);
    }
  }
  std::vector<std::unique_ptr<Upscaler>> upscalers;
  for (const auto& [entry, name] : entries) upscalers.push_back(make_upscaler(entry, name, options.scale));
  Dataset data = open_for(options.data, upscalers, options.eval.temporal);
  // 'classic' means the classic upscalers this data set can run: the BSP border upsampler only
  // where the renderer stored BSP border files (named on its own, evaluate() says why it cannot run).
  if (!data.info().bsp_border) {
    std::vector<std::unique_ptr<Upscaler>> kept;
    for (size_t i = 0; i < upscalers.size(); ++i)
      if (!(from_classic[i] && upscalers[i]->reads_bsp_border())) kept.push_back(std::move(upscalers[i]));
    upscalers = std::move(kept);
  }
  if (!options.scene.empty()) data = data.scene(options.scene);
  upscalers = in_precisions(std::move(upscalers), options.precisions, data, options.calibration);
  std::vector<EvalResult> results;
  nlohmann::ordered_json json;
  json["data"] = data.info().root.string();
  json["target"] = data.info().target;  // the ground truth every evaluation below measures against
  spdlog::info("{}: target {}", data.info().root.string(), data.info().target);
  if (!options.scene.empty()) json["scene"] = options.scene;
  json["evaluations"] = nlohmann::ordered_json::array();
  // Each model's figures are written as soon as its quality is known: at 1080p the latency of the
  // next models can take many minutes.
  const auto write_results = [&](const EvalResult& r) {
    if (!run_dir) return;
    write_file_atomic(run_dir->file("frames_" + r.name + ".csv"), frames_csv(r));
    std::vector<EvalResult> so_far = results;
    so_far.push_back(r);
    write_file_atomic(run_dir->file("summary.csv"), report_csv(group_results(so_far)));
  };
  for (auto& upscaler : upscalers) {
    EvalResult r = evaluate(*upscaler, data, options.eval, write_results);
    if (r.latency) spdlog::info("{}: latency {:.2f} ms (median of {})", r.name, r.latency->median_ms, r.latency->runs);
    json["evaluations"].push_back(to_json(r));
    if (data.scenes().size() > 1) {  // a multi-scene data set: quality per scene as well
      auto& per_scene = json["evaluations"].back()["scenes"];
      per_scene = nlohmann::ordered_json::array();
      for (const SceneScore& s : scene_scores(r, data)) {
        nlohmann::ordered_json j = {{"scene", s.scene}, {"frames", s.frames}};
        put_psnr(j, "psnr", s.psnr);
        j["ssim"] = s.ssim;
        j["identical_frames"] = s.identical_frames;
        per_scene.push_back(j);
        spdlog::info("{} on scene '{}': PSNR {:.3f} dB, SSIM {:.4f} on {} frame(s)", r.name, s.scene, s.psnr, s.ssim,
                     s.frames);
      }
    }
    results.push_back(std::move(r));
  }
  const auto tables = group_results(results);
  if (run_dir) write_file_atomic(run_dir->file("summary.csv"), report_csv(tables));
  for (const auto& t : tables) std::printf("%s\n", report_markdown(t).c_str());
  // Per table, its PSNR per frame as SVG beside results.json, named as the page finds it.
  json["tables"] = nlohmann::ordered_json::array();
  for (size_t i = 0; i < tables.size(); ++i) {
    std::string frame_plot;
    const auto per_frame = psnr_per_frame_plot(tables[i]);
    if (run_dir && per_frame) {
      frame_plot = psnr_per_frame_plot_name(table_file_stem(tables, i)) + ".svg";
      write_line_plot(run_dir->file(frame_plot), *per_frame);
    }
    json["tables"].push_back({{"dataset", tables[i].dataset},
                              {"scale", tables[i].scale},
                              {"target", tables[i].target},
                              {"rows", tables[i].rows.size()},
                              {"frame_plot_svg", frame_plot}});
  }
  json["comparisons"] = nlohmann::ordered_json::array();
  if (run_dir && options.images.frames > 0 && !results.empty())
    for (const auto& c : compare_frames(upscalers, data, results.front(), options.images, run_dir->path() / "images"))
      json["comparisons"].push_back(to_json(c));
  if (run_dir) write_report_page(run_dir->path(), json);
  return json;
}

std::vector<ComparisonImage> compare_eval_run(const std::filesystem::path& run, const ComparisonOptions& options,
                                              const std::filesystem::path& dir) {
  const auto config_file = run / "config.yaml";
  YAML::Node config;
  try {
    config = YAML::LoadFile(config_file.string());
  } catch (const YAML::Exception& e) {
    throw Error(config_file.string(), std::string("cannot read the run's config: ") + e.what());
  }
  if (!config["data"] || !config["models"])
    throw Error(config_file.string(), "names no data set and models: image comparisons need the run directory of "
                                      "cgsr eval (in a cgsr run, its eval/ or heldout/<scene>/eval/)");
  const auto models = config["models"].as<std::vector<std::string>>();
  const auto names = config["names"] ? config["names"].as<std::vector<std::string>>() : std::vector<std::string>{};
  const int scale = config["scale"] ? config["scale"].as<int>() : 2;
  std::vector<std::unique_ptr<Upscaler>> upscalers;
  for (size_t i = 0; i < models.size(); ++i)
    if (models[i] != "classic") upscalers.push_back(make_upscaler(models[i], i < names.size() ? names[i] : "", scale));
  Dataset data = open_for(config["data"].as<std::string>(), upscalers, /*temporal=*/false);
  if (config["scene"]) data = data.scene(config["scene"].as<std::string>());
  const auto evaluations = collect_evaluations({run.string()});
  if (evaluations.empty()) throw Error((run / "results.json").string(), "has no evaluation to show");
  return compare_frames(upscalers, data, evaluations.front(), options, dir);
}

}  // namespace cgsr
