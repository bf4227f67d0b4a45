#pragma once
// `cgsr render --config configs/scenes/NAME.yaml --out DIR`: renders a scene at every requested
// resolution into the cgsr dataset format (render_data/render_job.h, DATASET_FORMAT.md).
// Re-running the same command on a partly rendered DIR resumes it.

#include <CLI/CLI.hpp>

#include "cli/command.h"
#include "render_data/render_job.h"

namespace cgsr::cli {

struct RenderOptions : RunSettings, RenderJobOptions {};

config::Schema<RenderOptions> render_schema();
void setup_render(CLI::App& app);
nlohmann::ordered_json run_render(const RenderOptions& options, const std::filesystem::path& out);

}  // namespace cgsr::cli
