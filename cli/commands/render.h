#pragma once
// `cgsr render --config configs/scenes/NAME.yaml --out DIR`: renders a scene, or a scene set
// (`--scene a.yaml --scene b.yaml`), into a data set (the render job: pipeline/render_stage.h).
// Here: its flags.

#include <CLI/CLI.hpp>

namespace cgsr::cli {

void setup_render(CLI::App& app);

}  // namespace cgsr::cli
