// Frames per second of the software rasterizer on a real OpenArena level (default oa_dm1) at
// 640x480 on 2 threads, along the level's camera path; and the time to load the level.
// Needs the Debian packages openarena-088-data and openarena-data; without them each benchmark
// reports the install command as its error.
//
//   build-*/bench/bench_q3_render [--benchmark_filter=Render]
//   CGSR_BENCH_MAP=oa_rpg3dm2 build-*/bench/bench_q3_render
//
// items_per_second of BM_Q3Render is the frame rate.

#include <benchmark/benchmark.h>
#include <torch/torch.h>

#include <cstdlib>
#include <memory>
#include <optional>

#include "core/error.h"
#include "core/runtime.h"
#include "render_data/q3/q3_scene_source.h"
#include "render_data/renderer.h"

namespace {

using namespace cgsr;

std::string bench_map() {
  const char* map = std::getenv("CGSR_BENCH_MAP");
  return map && *map ? map : "oa_dm1";
}

struct LoadedLevel {
  SceneBundle bundle;
  q3::Q3SceneReport report;
  std::unique_ptr<SceneRenderer> renderer;
};

// Loaded once per process; an error is kept and reported by every benchmark.
const LoadedLevel* level(std::string& error) {
  static std::optional<LoadedLevel> loaded;
  static std::string failure;
  static bool tried = false;
  if (!tried) {
    tried = true;
    try {
      q3::Q3SceneOptions options;
      options.map = bench_map();
      LoadedLevel l;
      l.bundle = q3::load_q3_scene(options, 1, &l.report);
      RenderSettings settings;
      settings.shadows = false;  // the level is lit by lightmaps
      l.renderer = std::make_unique<SceneRenderer>(l.bundle.scene, settings);
      loaded = std::move(l);
    } catch (const Error& e) {
      failure = e.what();
    }
  }
  error = failure;
  return loaded ? &*loaded : nullptr;
}

void BM_Q3Render(benchmark::State& state) {
  set_threads(2);
  std::string error;
  const LoadedLevel* l = level(error);
  if (!l) return state.SkipWithError(error.c_str());
  const int width = static_cast<int>(state.range(0)), height = static_cast<int>(state.range(1));
  const int frames = 120;
  int frame = 0;
  for (auto _ : state) {
    const CameraPose pose = l->bundle.camera.at_frame(frame, frames);
    const CameraPose previous = l->bundle.camera.at_frame(frame - 1, frames);
    GBuffer g = l->renderer->render(pose, previous, width, height, l->bundle.camera.near_plane,
                                    l->bundle.camera.far_plane);
    benchmark::DoNotOptimize(g.color.data_ptr());
    frame = (frame + 1) % frames;
  }
  state.SetItemsProcessed(state.iterations());
  const auto& s = l->report.level;
  state.SetLabel(bench_map() + ": " + std::to_string(s.triangles) + " triangles, " + std::to_string(s.polygons) +
                 " polygons, " + std::to_string(s.patches) + " patches, " + std::to_string(s.meshes) + " meshes, " +
                 std::to_string(s.skipped()) + " skipped");
}
BENCHMARK(BM_Q3Render)->Args({640, 480})->Args({320, 240})->Unit(benchmark::kMillisecond)->MinTime(10)->UseRealTime();

void BM_Q3Load(benchmark::State& state) {
  set_threads(2);
  q3::Q3SceneOptions options;
  options.map = bench_map();
  for (auto _ : state) {
    try {
      SceneBundle b = q3::load_q3_scene(options, 1);
      benchmark::DoNotOptimize(b.scene.meshes.data());
    } catch (const Error& e) {
      return state.SkipWithError(e.what());
    }
  }
}
BENCHMARK(BM_Q3Load)->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
