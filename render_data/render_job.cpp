#include "render_data/render_job.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>

#include "core/error.h"
#include "render_data/bsp_border_file.h"
#include "render_data/frame_files.h"
#include "render_data/renderer.h"
#include "render_data/scene_source.h"

namespace cgsr {
namespace fs = std::filesystem;

config::Schema<EdgeSettings> edge_settings_schema() {
  config::Schema<EdgeSettings> s;
  s.field("depth_threshold", &EdgeSettings::depth_threshold,
          "relative error of the linear 1/depth prediction across a pixel pair that makes a depth edge")
      .range(1e-4, 10);
  s.field("crease_angle", &EdgeSettings::crease_angle, "normal angle between neighbours that makes a crease edge, degrees")
      .range(1, 180);
  s.field("id_changes", &EdgeSettings::id_changes, "object id changes are edges");
  return s;
}

config::Schema<BspBorderSettings> bsp_border_settings_schema() {
  config::Schema<BspBorderSettings> s;
  s.field("depth", &BspBorderSettings::depth, "lines on a root-to-leaf path of a border pixel's BSP (0: no BSP files)")
      .range(0, kMaxBspDepth);
  s.field("samples", &BspBorderSettings::samples,
          "samples per pixel side that find the surfaces in a pixel and colour the leaves (samples^2 per pixel)")
      .range(2, 16);
  return s;
}

std::vector<Resolution> parse_resolutions(const std::vector<std::string>& texts, const std::string& context) {
  std::vector<Resolution> out;
  for (const auto& t : texts) out.push_back(parse_resolution(t, context));
  if (out.empty()) throw Error(context, "needs at least one resolution");
  std::sort(out.begin(), out.end(), [](const Resolution& a, const Resolution& b) { return a.width < b.width; });
  for (size_t i = 1; i < out.size(); ++i) {
    const Resolution& lo = out.front();
    const Resolution& r = out[i];
    if (r == out[i - 1]) throw Error(context, "resolution " + r.name() + " is listed twice");
    if (r.width % lo.width != 0 || r.height % lo.height != 0 || r.width / lo.width != r.height / lo.height)
      throw Error(context, "resolution " + r.name() + " is not an integer scale of " + lo.name() +
                               " (every resolution must be s x the smallest, s an integer)");
  }
  return out;
}

std::string human_bytes(double bytes) {
  char buf[32];
  if (bytes >= 1e6) std::snprintf(buf, sizeof buf, "%.2f MB", bytes / 1e6);
  else std::snprintf(buf, sizeof buf, "%.1f KB", bytes / 1e3);
  return buf;
}

std::string render_fingerprint(const RenderJobOptions& o, uint64_t seed) {
  std::string text = config::to_yaml(o.scene.node) + "|" + std::to_string(o.frames) + "|" + std::to_string(seed) + "|" +
                     std::to_string(o.shadows) + "|" + std::to_string(o.shadow_map_size) + "|" +
                     std::to_string(o.edges.depth_threshold) + "|" + std::to_string(o.edges.crease_angle) + "|" +
                     std::to_string(o.edges.id_changes);
  for (const auto& r : o.resolutions) text += "|" + r;
  // Only when on: renders without BSP files keep the fingerprints they had before the option.
  if (o.bsp_border.enabled())
    text += "|bsp_border " + std::to_string(o.bsp_border.depth) + " " + std::to_string(o.bsp_border.samples);
  if (o.jitter.enabled()) text += "|jitter " + o.jitter.sequence + " " + std::to_string(o.jitter.phases);
  if (o.hr_samples != 1) text += "|hr_samples " + std::to_string(o.hr_samples) + " " + kHrFilterBox;
  return hex_fingerprint(text);
}

namespace {
// A killed render resumes; a directory with a render of something else is left alone.
void check_resumable(const fs::path& out, const std::string& fingerprint) {
  if (!has_manifest(out)) return;
  const DatasetManifest previous = read_manifest(out);
  if (previous.fingerprint != fingerprint)
    throw Error(out.string(), "holds a render of a different configuration (manifest fingerprint " + previous.fingerprint +
                                  ", this config " + fingerprint + "); render into another --out directory");
}
}  // namespace

RenderJobResult run_render_job(const RenderJobOptions& o, uint64_t seed, const fs::path& out,
                               const std::function<void(int, int)>& progress) {
  const auto started = std::chrono::steady_clock::now();
  const auto resolutions = parse_resolutions(o.resolutions, "resolutions");
  if (o.bsp_border.enabled())  // before anything is written
    check_bsp_border_settings(o.bsp_border, resolutions.front().width, resolutions.front().height);
  const int hr_side = hr_samples_per_side(o.hr_samples);
  if (hr_side == 0)
    throw Error("hr_samples", "is " + std::to_string(o.hr_samples) + ", must be " + hr_samples_expected());
  if (o.hr_samples > 1 && resolutions.size() < 2)
    throw Error("hr_samples", "supersamples the targets, every resolution but the smallest, and there is only " +
                                  resolutions.front().name() + ": list a larger resolution or drop hr_samples");
  const SceneBundle bundle = make_scene(o.scene, seed);

  RenderJobResult result;
  DatasetManifest& m = result.manifest;
  m.name = o.name.empty() ? bundle.scene.name : o.name;
  m.fingerprint = render_fingerprint(o, seed);
  m.frames = o.frames;
  m.resolutions = resolutions;
  m.near_plane = bundle.camera.near_plane;
  m.far_plane = bundle.camera.far_plane;
  m.vfov = bundle.camera.at_frame(0, o.frames).vfov;
  m.scene_source = config::block_type(o.scene);
  m.seed = seed;
  m.split = make_split(o.frames);
  if (o.bsp_border.enabled()) {
    m.bsp_border_depth = o.bsp_border.depth;
    m.bsp_border_samples = o.bsp_border.samples;
  }
  if (o.hr_samples > 1) {
    m.hr_samples = o.hr_samples;
    m.hr_filter = kHrFilterBox;
  }
  if (o.jitter.enabled()) {
    m.jitter_sequence = o.jitter.sequence;
    m.jitter_phases = o.jitter.phases;
    for (int f = 0; f < o.frames; ++f) {
      const Vec2 j = jitter_offset(o.jitter, f);
      m.jitter_offsets.push_back({j.x, j.y});
    }
  }

  fs::create_directories(out);
  check_resumable(out, m.fingerprint);
  write_manifest(out, m);  // complete: false until every frame is written

  RenderSettings settings;
  settings.shadows = o.shadows;
  settings.shadow.map_size = o.shadow_map_size;
  settings.edges = o.edges;
  const SceneRenderer renderer(bundle.scene, settings);
  result.triangles = renderer.geometry().triangle_count();
  spdlog::info("scene '{}': {} triangles, {} lights, {} textures; {} frames at {}", bundle.scene.name, result.triangles,
               bundle.scene.lights.size(), bundle.scene.textures.size(), o.frames, join(o.resolutions));
  if (hr_side > 1)
    spdlog::info("colour above {}: {}, rendered at {}x the resolution", resolutions.front().name(),
                 hr_target_description(o.hr_samples, kHrFilterBox), hr_side);

  const auto& kinds = all_file_kinds();
  result.bytes_per_kind.assign(resolutions.size(), std::vector<double>(kinds.size(), 0.0));
  const bool bsp = o.bsp_border.enabled();
  const Resolution& lr = resolutions.front();
  size_t bsp_pixels = 0, bsp_lines = 0;
  result.motion_rejected.assign(resolutions.size(), {});
  for (int f = 0; f < o.frames; ++f) {
    const fs::path bsp_file = bsp_border_file(out, lr, f);
    if (frame_complete(out, resolutions, f) && (!bsp || fs::exists(bsp_file))) {
      ++result.skipped;
      if (bsp) {  // counted from the file, so resumed frames count too
        const BspBorderImage image = read_bsp_border_file(bsp_file, f, lr);
        bsp_pixels += image.size();
        bsp_lines += image.line_count();
      }
    } else {
      const CameraPose pose = bundle.camera.at_frame(f, o.frames), previous = bundle.camera.at_frame(f - 1, o.frames);
      for (size_t ri = 0; ri < resolutions.size(); ++ri) {
        const Resolution& r = resolutions[ri];
        // Only the smallest resolution is jittered: the others are ground truth.
        const Vec2 jitter = ri == 0 ? jitter_offset(o.jitter, f) : Vec2{0, 0};
        GBuffer g = renderer.render(pose, previous, r.width, r.height, m.near_plane, m.far_plane, jitter);
        // The targets' colour supersampled; their G-buffers stay render()'s one sample per pixel.
        if (ri > 0 && hr_side > 1)
          g.color = renderer.render_color(pose, r.width, r.height, m.near_plane, m.far_plane, hr_side);
        write_frame_files(out, r, f, g);
        auto& rejected = result.motion_rejected[ri];
        rejected.pixels += g.motion_rejected;
        rejected.max_per_frame = std::max(rejected.max_per_frame, g.motion_rejected);
        rejected.frames += g.motion_rejected > 0;
        rejected.clamped += g.motion_clamped;
      }
      // After the frame's images: an existing BSP file marks the frame complete.
      if (bsp) {
        const BspBorderImage image =
            renderer.render_bsp_border(pose, lr.width, lr.height, m.near_plane, m.far_plane, o.bsp_border);
        write_bsp_border_file(bsp_file, image);
        bsp_pixels += image.size();
        bsp_lines += image.line_count();
      }
      ++result.rendered;
    }
    if (bsp) result.bsp_border_bytes += static_cast<double>(fs::file_size(bsp_file));
    // Sizes from disk, so resumed frames count too.
    for (size_t ri = 0; ri < resolutions.size(); ++ri)
      for (size_t k = 0; k < kinds.size(); ++k)
        result.bytes_per_kind[ri][k] += static_cast<double>(fs::file_size(frame_file(out, resolutions[ri], kinds[k], f)));
    if (progress) progress(f + 1, o.frames);
  }
  for (size_t ri = 0; ri < resolutions.size(); ++ri) {
    double total = 0;
    for (auto& b : result.bytes_per_kind[ri]) total += (b /= o.frames);
    m.bytes_per_frame.push_back(total);
  }
  if (bsp) {
    result.bsp_border_bytes /= o.frames;
    m.bytes_per_frame.front() += result.bsp_border_bytes;
    result.bsp_border_fraction = static_cast<double>(bsp_pixels) / (static_cast<double>(lr.width) * lr.height * o.frames);
    result.bsp_border_lines = bsp_pixels ? static_cast<double>(bsp_lines) / static_cast<double>(bsp_pixels) : 0.0;
  }
  write_manifest(out, m);  // with the sizes, still complete: false (finish_render)
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  if (result.skipped > 0) spdlog::info("resumed: {} frame(s) were already complete", result.skipped);
  for (size_t ri = 0; ri < resolutions.size(); ++ri) {
    std::string parts;
    for (size_t k = 0; k < kinds.size(); ++k)
      parts += (k ? ", " : "") + file_kind_name(kinds[k]) + " " + human_bytes(result.bytes_per_kind[ri][k]);
    if (bsp && ri == 0) parts += ", bsp_border " + human_bytes(result.bsp_border_bytes);
    spdlog::info("size per frame at {}: {} ({})", resolutions[ri].name(), human_bytes(m.bytes_per_frame[ri]), parts);
  }
  for (size_t ri = 0; ri < resolutions.size(); ++ri) {
    const auto& mr = result.motion_rejected[ri];
    if (mr.pixels > 0)
      spdlog::info("motion at {}: {} pixel(s) in {} of {} rendered frame(s) (at most {} in one) were behind the "
                   "previous camera's near plane: motion 0",
                   resolutions[ri].name(), mr.pixels, mr.frames, result.rendered, mr.max_per_frame);
    if (mr.clamped > 0)
      spdlog::info("motion at {}: {} pixel(s) came from beyond one image size outside the previous frame: cut there",
                   resolutions[ri].name(), mr.clamped);
  }
  if (bsp) {
    const double raw = 3.0 * lr.width * lr.height;  // the colour image as 8-bit RGB
    const double png = result.bytes_per_kind[0][static_cast<size_t>(FileKind::Color)];
    spdlog::info("bsp_border at {}: {:.2f}% of the pixels are border pixels, {:.2f} lines each; {} per frame = {:.1f}% "
                 "of the colour image's {} raw bytes ({:.1f}% of its PNG)",
                 lr.name(), 100.0 * result.bsp_border_fraction, result.bsp_border_lines, human_bytes(result.bsp_border_bytes),
                 100.0 * result.bsp_border_bytes / raw, static_cast<int64_t>(raw), 100.0 * result.bsp_border_bytes / png);
  }
  return result;
}

SceneSetRenderResult run_scene_set_render(const std::string& name, const std::vector<SceneRenderJob>& jobs,
                                          uint64_t seed, const fs::path& out,
                                          const std::function<void(int, int)>& progress) {
  const auto started = std::chrono::steady_clock::now();
  if (jobs.empty()) throw Error(out.string(), "a scene set needs at least one scene");
  const auto resolutions = parse_resolutions(jobs.front().options.resolutions, jobs.front().origin + ": resolutions");
  std::vector<ManifestScene> scenes;
  std::vector<FrameSplit> splits;
  std::vector<std::string> names;
  int total = 0;
  for (const auto& job : jobs) {
    const RenderJobOptions& o = job.options;
    // The name is a directory name under scenes/.
    const bool plain = !o.name.empty() && o.name[0] != '.' &&
                       std::all_of(o.name.begin(), o.name.end(), [](unsigned char c) {
                         return std::isalnum(c) || c == '-' || c == '_' || c == '.';
                       });
    if (!plain)
      throw Error(job.origin, "scene name '" + o.name + "' must be letters, digits, '-', '_' or '.' (it names the "
                              "scene's directory); set the scene's name");
    for (const auto& other : jobs) {
      if (&other == &job) break;
      if (other.options.name == o.name)
        throw Error(job.origin, "scene name '" + o.name + "' is also the name of the scene from " + other.origin +
                                    "; give one of them another name");
    }
    if (parse_resolutions(o.resolutions, job.origin + ": resolutions") != resolutions)
      throw Error(job.origin, "renders at " + join(o.resolutions) + ", but " + jobs.front().origin + " at " +
                              join(jobs.front().options.resolutions) + ": every scene of a set needs the same resolutions");
    scenes.push_back({o.name, "scenes/" + o.name, render_fingerprint(o, seed), 0, o.frames, job.weight});
    splits.push_back(make_split(o.frames));
    names.push_back(o.name);
    total += o.frames;
  }
  SceneSetRenderResult result;
  DatasetManifest& m = result.manifest;
  m = scene_set_manifest(name.empty() ? join(names, "+") : name, resolutions, scenes, splits);
  fs::create_directories(out);
  check_resumable(out, m.fingerprint);
  write_manifest(out, m);  // complete: false until every scene is
  int done = 0;
  for (const auto& job : jobs) {
    spdlog::info("scene {}/{}: '{}' ({})", result.scenes.size() + 1, jobs.size(), job.options.name, job.origin);
    const fs::path scene_dir = out / "scenes" / job.options.name;
    result.scenes.push_back(run_render_job(job.options, seed, scene_dir, [&](int, int) {
      if (progress) progress(++done, total);
    }));
    finish_render(scene_dir, result.scenes.back().manifest);  // nothing else is written into a scene's directory
    result.rendered += result.scenes.back().rendered;
    result.skipped += result.scenes.back().skipped;
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return result;
}

void finish_render(const fs::path& out, DatasetManifest manifest) {
  manifest.complete = true;
  write_manifest(out, manifest);
}

}  // namespace cgsr
