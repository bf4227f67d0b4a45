#include "cli/commands/render.h"

#include <spdlog/spdlog.h>

#include "core/progress.h"

namespace cgsr::cli {

config::Schema<RenderOptions> render_schema() {
  config::Schema<RenderOptions> s;
  add_render_job_fields(s);
  add_run_settings(s);
  return s;
}

void setup_render(CLI::App& app) {
  add_command<RenderOptions>(
      app, "render", "Render a scene config into a dataset (LR/HR colour, depth, normals, edges, motion)",
      render_schema,
      [](CLI::App& sub, std::vector<FlagAssignment>& flags) {
        flag_to_key(sub, flags, "--frames", "frames", "frames to render");
        flag_to_key(sub, flags, "--resolutions", "resolutions", "resolutions, e.g. [320x240,640x480]");
      },
      [](const RenderOptions& options, const YAML::Node&, RunDir* run_dir) {
        return run_render(options, run_dir->path());
      },
      /*always_run_dir=*/true);
}

nlohmann::ordered_json run_render(const RenderOptions& options, const std::filesystem::path& out) {
  Progress progress("render", options.frames);
  const RenderJobResult r = run_render_job(options, static_cast<uint64_t>(options.seed), out,
                                           [&progress](int, int) { progress.advance(); });
  progress.finish();
  nlohmann::ordered_json j;
  j["dataset"] = out.string();
  j["name"] = r.manifest.name;
  j["frames"] = r.manifest.frames;
  j["rendered"] = r.rendered;
  j["resumed"] = r.skipped;
  j["seconds"] = r.seconds;
  j["triangles"] = r.triangles;
  auto& sizes = j["bytes_per_frame"];
  const auto& kinds = all_file_kinds();
  for (size_t i = 0; i < r.manifest.resolutions.size(); ++i) {
    auto& entry = sizes[r.manifest.resolutions[i].name()];
    entry["total"] = r.manifest.bytes_per_frame[i];
    for (size_t k = 0; k < kinds.size(); ++k) entry[file_kind_name(kinds[k])] = r.bytes_per_kind[i][k];
  }
  std::printf("rendered %d frame(s) (%d resumed) of '%s' into %s in %.1f s\n", r.rendered, r.skipped,
              r.manifest.name.c_str(), out.string().c_str(), r.seconds);
  for (size_t i = 0; i < r.manifest.resolutions.size(); ++i)
    std::printf("  %-10s %s per frame\n", r.manifest.resolutions[i].name().c_str(),
                human_bytes(r.manifest.bytes_per_frame[i]).c_str());
  return j;
}

}  // namespace cgsr::cli
