#include "pipeline/render_stage.h"

#include <spdlog/spdlog.h>

#include "core/error.h"
#include "core/progress.h"
#include "core/text.h"
#include "render_data/scene_source.h"

namespace cgsr {

namespace {
config::Schema<SceneSetEntry> scene_set_entry_schema() {
  config::Schema<SceneSetEntry> s;
  s.field("config", &SceneSetEntry::config, "the scene's render config file").required();
  s.field("name", &SceneSetEntry::name, "scene name, also its directory (default: the config's name)");
  s.field("weight", &SceneSetEntry::weight, "sampling weight (0 for every scene: in proportion to training frames)")
      .at_least(0);
  s.field("frames", &SceneSetEntry::frames, "frames to render (0: the config's)").range(0, 1000000);
  s.field("set", &SceneSetEntry::set, "overrides of the scene config, key.path=value as --set (e.g. scene.variant=3)");
  // Entries without overrides resolve as before the key existed.
  s.omit_when("set", [](const SceneSetEntry& e) { return e.set.empty(); });
  return s;
}

// The keys that each scene's own config sets in a scene set.
const std::vector<std::string> kPerSceneKeys = {"frames", "resolutions", "shadows", "shadow_map_size", "edges",
                                               "bsp_border"};
}  // namespace

config::Schema<RenderOptions> render_schema() {
  config::Schema<RenderOptions> s;
  add_render_job_fields(s, /*scene_required=*/false);
  s.list("scenes", &RenderOptions::scenes, scene_set_entry_schema(),
         "a scene set instead of 'scene': [{config, name, weight, frames, set}], rendered into one data set");
  s.validate([](const RenderOptions& o, const config::Cursor& at, const YAML::Node& node) {
    const bool has_scene = o.scene.node && !o.scene.node.IsNull();
    if (o.scenes.empty()) {
      if (!has_scene) at.child("scene").fail(node, "missing required key 'scene' (or 'scenes' for a scene set)");
      return;
    }
    if (has_scene) at.child("scene").fail(node["scene"], "give 'scene' (one scene) or 'scenes' (a scene set), not both");
    for (const auto& key : kPerSceneKeys)
      if (node[key])
        at.child(key).fail(node[key], "in a scene set, '" + key + "' is each scene's own (its config; an entry may set frames)");
    for (size_t i = 0; i < o.scenes.size(); ++i)
      if (!std::filesystem::is_regular_file(o.scenes[i].config))
        at.child("scenes").index(i).child("config").fail(node["scenes"][i], "no such scene config file '" + o.scenes[i].config + "'");
  });
  // A single scene's resolved config (and so `cgsr run`'s stage hash) is what it was before scene
  // sets; a scene set's lists the scenes only.
  s.omit_when("scenes", [](const RenderOptions& o) { return o.scenes.empty(); });
  for (const auto& key : kPerSceneKeys) s.omit_when(key, [](const RenderOptions& o) { return !o.scenes.empty(); });
  s.omit_when("scene", [](const RenderOptions& o) { return !o.scenes.empty(); });
  add_run_settings(s);
  return s;
}

std::vector<SceneRenderJob> scene_set_jobs(const RenderOptions& options) {
  std::vector<SceneRenderJob> jobs;
  for (const auto& entry : options.scenes) {
    config::Document document = config::Document::load_file(entry.config);
    for (const auto& assignment : entry.set) document.apply_override(assignment, entry.config + ": set " + assignment);
    const RenderOptions scene = config::parse_document(document, render_schema());
    if (!scene.scenes.empty()) throw Error(entry.config, "is a scene set itself; list its scene configs instead");
    SceneRenderJob job;
    job.options = scene;
    job.options.name = !entry.name.empty() ? entry.name
                       : !scene.name.empty() ? scene.name
                                             : std::filesystem::path(entry.config).stem().string();
    if (entry.frames > 0) job.options.frames = entry.frames;
    job.weight = entry.weight;
    job.origin = entry.config;
    jobs.push_back(std::move(job));
  }
  return jobs;
}

namespace {
nlohmann::ordered_json sizes_json(const RenderJobResult& r) {
  nlohmann::ordered_json sizes;
  const auto& kinds = all_file_kinds();
  for (size_t i = 0; i < r.manifest.resolutions.size(); ++i) {
    auto& entry = sizes[r.manifest.resolutions[i].name()];
    entry["total"] = r.manifest.bytes_per_frame[i];
    for (size_t k = 0; k < kinds.size(); ++k) entry[file_kind_name(kinds[k])] = r.bytes_per_kind[i][k];
    if (i == 0 && r.manifest.bsp_border_depth > 0) entry["bsp_border"] = r.bsp_border_bytes;
  }
  return sizes;
}

// The memory cost of the BSP border files against the colour image they refine; null without them.
nlohmann::ordered_json bsp_border_json(const RenderJobResult& r) {
  if (r.manifest.bsp_border_depth == 0) return nullptr;
  const Resolution& lr = r.manifest.resolutions.front();
  const double raw = 3.0 * lr.width * lr.height;
  const double png = r.bytes_per_kind[0][static_cast<size_t>(FileKind::Color)];
  return {{"resolution", lr.name()},
          {"depth", r.manifest.bsp_border_depth},
          {"samples", r.manifest.bsp_border_samples},
          {"bytes_per_frame", r.bsp_border_bytes},
          {"border_pixel_fraction", r.bsp_border_fraction},
          {"lines_per_border_pixel", r.bsp_border_lines},
          {"color_raw_bytes", raw},
          {"color_png_bytes_per_frame", png},
          {"fraction_of_color_raw", r.bsp_border_bytes / raw},
          {"fraction_of_color_png", png > 0 ? r.bsp_border_bytes / png : 0.0}};
}

// Per resolution, the pixels whose point was behind the previous camera's near plane (motion 0)
// and those whose motion was cut at the guard band, over the frames rendered in this run.
nlohmann::ordered_json motion_rejected_json(const RenderJobResult& r) {
  nlohmann::ordered_json j;
  j["frames_counted"] = r.rendered;
  for (size_t i = 0; i < r.motion_rejected.size(); ++i)
    j[r.manifest.resolutions[i].name()] = {{"pixels", r.motion_rejected[i].pixels},
                                           {"max_per_frame", r.motion_rejected[i].max_per_frame},
                                           {"frames", r.motion_rejected[i].frames},
                                           {"clamped_pixels", r.motion_rejected[i].clamped}};
  return j;
}

// What every render reports, of one scene or a set.
nlohmann::ordered_json render_summary(const std::filesystem::path& out, const DatasetManifest& manifest, int rendered,
                                      int resumed, double seconds) {
  nlohmann::ordered_json j;
  j["dataset"] = out.string();
  j["name"] = manifest.name;
  j["frames"] = manifest.frames;
  j["rendered"] = rendered;
  j["resumed"] = resumed;
  j["seconds"] = seconds;
  return j;
}

// A render's results and its manifest, which finish_render marks complete.
struct Rendered {
  nlohmann::ordered_json summary;
  DatasetManifest manifest;
};

Rendered render_scene_set(const RenderOptions& options, const std::filesystem::path& out) {
  const auto jobs = scene_set_jobs(options);
  int total = 0;
  for (const auto& job : jobs) total += job.options.frames;
  Progress progress("render", total);
  const SceneSetRenderResult r = run_scene_set_render(options.name, jobs, static_cast<uint64_t>(options.seed), out,
                                                      [&progress](int, int) { progress.advance(); });
  progress.finish();
  nlohmann::ordered_json j = render_summary(out, r.manifest, r.rendered, r.skipped, r.seconds);
  j["scenes"] = nlohmann::ordered_json::array();
  std::printf("rendered %d frame(s) (%d resumed) of %zu scenes as '%s' into %s in %.1f s\n", r.rendered, r.skipped,
              r.scenes.size(), r.manifest.name.c_str(), out.string().c_str(), r.seconds);
  for (size_t i = 0; i < r.scenes.size(); ++i) {
    const RenderJobResult& s = r.scenes[i];
    const ManifestScene& entry = r.manifest.scenes[i];
    j["scenes"].push_back({{"name", entry.name},
                           {"frames", entry.frames},
                           {"first_frame", entry.first_frame},
                           {"weight", entry.weight},
                           {"rendered", s.rendered},
                           {"resumed", s.skipped},
                           {"triangles", s.triangles},
                           {"bytes_per_frame", sizes_json(s)},
                           {"motion_rejected", motion_rejected_json(s)}});
    if (s.manifest.bsp_border_depth > 0) j["scenes"].back()["bsp_border"] = bsp_border_json(s);
    std::string sizes;
    for (size_t k = 0; k < s.manifest.resolutions.size(); ++k)
      sizes += (k ? ", " : "") + s.manifest.resolutions[k].name() + " " + human_bytes(s.manifest.bytes_per_frame[k]);
    std::printf("  %-16s frames %d..%d (train %zu / val %zu / test %zu), %s per frame\n", entry.name.c_str(),
                entry.first_frame, entry.first_frame + entry.frames - 1, s.manifest.split.train.size(),
                s.manifest.split.val.size(), s.manifest.split.test.size(), sizes.c_str());
  }
  return {j, r.manifest};
}

Rendered render_one_scene(const RenderOptions& options, const std::filesystem::path& out) {
  Progress progress("render", options.frames);
  const RenderJobResult r = run_render_job(options, static_cast<uint64_t>(options.seed), out,
                                           [&progress](int, int) { progress.advance(); });
  progress.finish();
  nlohmann::ordered_json j = render_summary(out, r.manifest, r.rendered, r.skipped, r.seconds);
  j["triangles"] = r.triangles;
  j["target"] = hr_target_description(r.manifest.hr_samples, r.manifest.hr_filter);
  j["bytes_per_frame"] = sizes_json(r);
  j["motion_rejected"] = motion_rejected_json(r);
  if (r.manifest.bsp_border_depth > 0) j["bsp_border"] = bsp_border_json(r);
  std::printf("rendered %d frame(s) (%d resumed) of '%s' into %s in %.1f s\n", r.rendered, r.skipped,
              r.manifest.name.c_str(), out.string().c_str(), r.seconds);
  for (size_t i = 0; i < r.manifest.resolutions.size(); ++i)
    std::printf("  %-10s %s per frame\n", r.manifest.resolutions[i].name().c_str(),
                human_bytes(r.manifest.bytes_per_frame[i]).c_str());
  return {j, r.manifest};
}

Rendered render(const RenderOptions& options, const std::filesystem::path& out) {
  return options.scenes.empty() ? render_one_scene(options, out) : render_scene_set(options, out);
}
}  // namespace

std::string check_render(const RenderOptions& options) {
  std::vector<SceneRenderJob> jobs;
  if (options.scenes.empty()) {
    jobs.push_back({options, 0, ""});
  } else {
    jobs = scene_set_jobs(options);
  }
  std::string out;
  for (const auto& job : jobs) {
    const std::string at = job.origin.empty() ? "" : job.origin + ": ";
    const auto resolutions = parse_resolutions(job.options.resolutions, at + "resolutions");
    if (job.options.bsp_border.enabled())
      check_bsp_border_settings(job.options.bsp_border, resolutions.front().width, resolutions.front().height);
    const SceneBundle bundle = make_scene(job.options.scene, static_cast<uint64_t>(options.seed));
    out += at + "scene '" + bundle.scene.name + "', " + std::to_string(triangle_count(bundle.scene)) + " triangles, " +
           std::to_string(job.options.frames) + " frames at " + join(job.options.resolutions) + "\n";
  }
  return out;
}

nlohmann::ordered_json run_render(const RenderOptions& options, const std::filesystem::path& out) {
  Rendered r = render(options, out);
  finish_render(out, r.manifest);
  return r.summary;
}

nlohmann::ordered_json run_render(const RenderOptions& options, RunDir& run_dir) {
  Rendered r = render(options, run_dir.path());
  run_dir.after_results([out = run_dir.path(), manifest = r.manifest] { finish_render(out, manifest); });
  return r.summary;
}

}  // namespace cgsr
