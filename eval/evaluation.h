#pragma once
// Evaluation of any upscaler on full frames of a data set split: per-frame PSNR/SSIM (docs/design.md
// convention), PSNR on geometry edges and on the rest of the frame (the HR edge channel grown by
// one pixel, edges.h; needs the dataset to carry edges at HR, whatever the upscaler reads),
// temporal stability (warping error between consecutive outputs using the rendered motion
// vectors, next to the same figure for the ground truth), and latency at the frame size.

#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/metrics.h"
#include "core/timing.h"
#include "eval/upscaler.h"
#include "render_data/dataset.h"

namespace cgsr {

struct EvalOptions {
  std::string split = "test";
  int max_frames = 0;          // 0 = every frame of the split
  std::string frames;          // "A:B": only frame indices A <= i < B of the split ("" = all)
  int crop_border = 0;         // pixels (HR) ignored at each side
  bool y_channel = false;      // PSNR/SSIM on BT.601 luma instead of RGB
  bool temporal = true;        // needs motion vectors and the previous frame
  int latency_runs = 10;       // timed runs (after 2 warm-up runs) over that many frames in turn; 0 = skip
  std::string save_frames;     // directory for SR frames as PNG; "" = do not save
};
config::Schema<EvalOptions> eval_schema_fields();

// The frame indices `options` selects from `data` (split, frames range, max_frames); throws
// naming the range when it selects nothing.
std::vector<int> evaluation_frames(const Dataset& data, const EvalOptions& options);

struct FrameScore {
  int frame = 0;
  double psnr = 0, ssim = 0;
  // PSNR on the dilated HR edge pixels and on the others, and the edge pixels' share of the
  // compared pixels; none without an edge channel (or, for one side, without pixels there).
  std::optional<double> psnr_edge, psnr_rest, edge_fraction;
  std::optional<double> temporal_error, temporal_error_reference;  // none for the first frame
  std::optional<PatternChoice> choice;  // Upscaler::frame_choice() of this frame (none for most upscalers)
};

// Where a scene of the data set begins: the set's index of its first frame, where a temporal
// upscaler's history starts again (a scene cut).
struct SceneStart {
  std::string scene;
  int first_frame = 0;
};

struct EvalResult {
  std::string name;
  Precision precision = Precision::Fp32;  // of a network's row ("<network> int8")
  std::string dataset;  // the data set's scene name
  // The ground truth measured against (DatasetInfo::target): "aliased (1 sample per pixel)",
  // "supersampled (4 samples per pixel, box filter)", "as captured"; empty in older results.
  std::string target;
  std::string split;
  int scale = 2;
  int64_t lr_width = 0, lr_height = 0;
  std::vector<FrameScore> frames;
  // The scenes holding evaluated frames, in frame order: which scene each frame belongs to (the
  // last one starting at or before it). Empty in results written before it: one scene.
  std::vector<SceneStart> scene_starts;
  double psnr = 0, ssim = 0;  // means over frames (PSNR of identical frames excluded, counted)
  int identical_frames = 0;
  // Means over the frames that have them (infinite values excluded like psnr's; +inf when
  // every one is infinite).
  std::optional<double> psnr_edge, psnr_rest, edge_fraction;
  std::optional<double> temporal_error, temporal_error_reference;
  std::optional<LatencyStats> latency;
  // The exported ONNX file of the network in ONNX Runtime on the same input (what a game would
  // ship); set by the report stage of `cgsr run`.
  std::optional<LatencyStats> onnxruntime_latency;
  std::optional<Complexity> cost;
};

// At most `count` (and 16) of `frames`, spread over them, as the upscaler reads them: what
// latency is timed on, frame after frame. An upscaler that reads the previous frame (a
// hybrid-pruned model chooses its pattern from the change) is shown each frame's predecessor
// first, as evaluate() does, so that it is timed on the choices it was evaluated with.
struct TimingSequence {
  std::vector<Batch> frames;
  // previous[i]: the frame before frames[i], an empty Batch when it has none (the upscaler's
  // history is then reset); no entries when the upscaler reads no previous frame.
  std::vector<Batch> previous;

  size_t size() const { return frames.size(); }
  // Upscales frame i (after showing the upscaler its predecessor).
  torch::Tensor run(Upscaler& upscaler, size_t i) const;
};
TimingSequence timing_sequence(const Dataset& data, const std::vector<int>& frames, int scale,
                               const Upscaler& upscaler, int count);

// A recurrent upscaler (Upscaler::recurrent) brought up to `frame`: the frames of its scene before
// it run in order, from `last_run` + 1 when `last_run` is an earlier frame of that scene (the last
// frame it ran), else from the scene's first frame after reset_history(). Returns its output for
// frame - 1 (clamped to [0,1]) when it ran that frame here; `last_run` becomes `frame`. Batches
// are built with `channels` in `depth`.
torch::Tensor run_up_to(Upscaler& upscaler, const Dataset& data, int frame, int scale,
                        const std::vector<RenderChannel>& channels, DepthEncoding depth, int& last_run);

// `on_quality` is called once the quality figures are known, before the latency is measured
// (which can take minutes at 1080p), so callers can write them out early.
EvalResult evaluate(Upscaler& upscaler, const Dataset& dataset, const EvalOptions& options,
                    const std::function<void(const EvalResult&)>& on_quality = {});

// The evaluated frames of `result` by the scene of `data` they belong to, in scene order (scenes
// with no evaluated frame left out): mean PSNR (identical frames excluded and counted, as in the
// overall PSNR) and SSIM.
struct SceneScore {
  std::string scene;
  int frames = 0, identical_frames = 0;
  double psnr = 0, ssim = 0;
};
std::vector<SceneScore> scene_scores(const EvalResult& result, const Dataset& data);

nlohmann::ordered_json to_json(const EvalResult& result);
EvalResult eval_result_from_json(const nlohmann::ordered_json& j, const std::string& context);
std::string frames_csv(const EvalResult& result);

}  // namespace cgsr
