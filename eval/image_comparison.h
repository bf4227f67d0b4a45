#pragma once
// Pictures of results: for one frame, a crop of every upscaler's output at the same region next
// to the LR input (nearest), the classic upscalers and the ground truth, and a map of each
// one's absolute error on one colour scale. The region is where the networks' outputs differ
// most from bicubic, unless the options fix it. The report shows them for the test frames with
// the most geometry edges (where networks win or lose most) and a frame of each held-out scene.
//
//   const auto frames = frames_with_most_edges(bicubic_result, 3);
//   for (int f : frames) images.push_back(compare_frame(networks, data, f, {}, dir / "images"));

#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "core/config.h"
#include "eval/evaluation.h"
#include "eval/upscaler.h"
#include "render_data/dataset.h"

namespace cgsr {

struct ComparisonOptions {
  int frames = 3;       // test frames compared (those with the most geometry-edge pixels); 0 = none
  int crop = 96;        // side of the square crop, HR pixels
  int zoom = 2;         // each crop pixel drawn as zoom x zoom
  std::vector<int> at;  // [x, y]: the crop's top-left corner in HR pixels; empty = chosen
};
config::Schema<ComparisonOptions> comparison_schema_fields();
// The options of commands that compare no frame unless asked (cgsr eval, cgsr report).
inline ComparisonOptions no_comparisons() {
  ComparisonOptions o;
  o.frames = 0;
  return o;
}

// The `count` frames of `result` with the most geometry-edge pixels, most first (ties: the
// earlier frame); the first `count` frames when it has no edge figures.
std::vector<int> frames_with_most_edges(const EvalResult& result, int count);

// The top-left corner of the size x size window where the errors of `outputs` against `truth`
// differ most from the error of `reference` (per pixel the absolute error, colour channels
// averaged; summed over the window and the outputs), searched on a grid of size/8 steps; ties go
// to the first in row order. Where they differ in error, not merely in pixels: aliasing that
// every upscaler gets wrong in its own way shows no quality difference. Tensors are [1, 3, H, W].
cv::Point choose_crop(const std::vector<torch::Tensor>& outputs, const torch::Tensor& reference,
                      const torch::Tensor& truth, int size);

// One colour scale for the error maps of all `outputs` against `truth`: the 99th percentile of
// their absolute errors (colour channels averaged) within `region`, at least 1/255.
double shared_error_scale(const std::vector<torch::Tensor>& outputs, const torch::Tensor& truth, const cv::Rect& region);

// The absolute error (colour channels averaged) coloured on [0, scale] (inferno), BGR.
cv::Mat error_map(const torch::Tensor& output, const torch::Tensor& truth, const cv::Rect& region, double scale);

struct ComparisonImage {
  std::string dataset;
  int frame = 0;
  cv::Rect region;          // HR pixels
  double error_scale = 0;   // the error maps' shared colour scale (absolute error at the top)
  std::string crops, errors;  // file names, next to each other
  std::vector<std::pair<std::string, double>> crop_psnr;  // per upscaler, PSNR within the crop
};
nlohmann::ordered_json to_json(const ComparisonImage& image);
ComparisonImage comparison_from_json(const nlohmann::ordered_json& j, const std::string& context);

// Upscales `frame` of `data` by `scale` with the classic upscalers (nearest, bicubic, fsr) and
// `networks` (may be none), and writes <dataset>_frame<N>_crops.png and _errors.png into `dir`.
ComparisonImage compare_frame(const std::vector<Upscaler*>& networks, const Dataset& data, int frame, int scale,
                              const ComparisonOptions& options, const std::filesystem::path& dir);

}  // namespace cgsr
