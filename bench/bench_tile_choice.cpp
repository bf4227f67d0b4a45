// Would a hybrid gain by choosing its pattern per tile instead of per frame? The bound, before
// building a tiled runner: every pattern of a hybrid-pruned model upscales every frame whole, each
// frame is cut into square tiles, and each tile takes one pattern's output. No margins and no
// seams, so a tiled run can only do worse. A frame's cost is the area-weighted mean latency of its
// tiles' patterns (the patterns' latency measured when the model was pruned).
//
//   bench_tile_choice --model runs/quickstart/prune/pruned.cgsr --data runs/quickstart/data
//     [--split test] [--frames A:B] [--tile 40] [--threads N]
//
// Choosers, each swept over its budget, on the same outputs:
//   - oracle per tile: each tile the pattern minimizing its squared error + lambda * cost (the best
//     any per-tile rule can do, up to the Lagrangian's convex hull);
//   - edges per tile: the share p of tiles with the most HR geometry-edge pixels takes a wider
//     pattern, the rest a narrower one (a rule the renderer's edge map allows), every pair and p;
//   - detail per tile: the same, ranking tiles by the LR frame's mean absolute colour gradient;
//   - oracle per frame: the same Lagrangian with one pattern per frame (what the hybrid chooses).
// Prints each pattern alone and each chooser's best PSNR at no more than that pattern's cost.
#include <CLI/CLI.hpp>
#include <torch/torch.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "core/metrics.h"
#include "core/runtime.h"
#include "eval/evaluation.h"
#include "pruning/hybrid_model.h"
#include "pruning/pattern_networks.h"
#include "render_data/dataset.h"
#include "render_data/patch_sampler.h"
#include "render_data/render_channels.h"

using namespace cgsr;

namespace {

struct Point {
  double cost = 0, psnr = 0;  // mean over frames: cost in ms, PSNR in dB
};

// One test frame, every pattern's output and its tiles.
struct TiledFrame {
  std::vector<torch::Tensor> outputs;         // [pattern] clamped HR output, [1, 3, H, W]
  torch::Tensor hr;
  std::vector<std::array<int64_t, 2>> tiles;  // {y, x} of each tile's top-left HR pixel
  std::vector<std::vector<double>> sse;       // [pattern][tile] squared error
  // Per tile: share of geometry-edge pixels, mean LR colour gradient, share of the frame's area.
  std::vector<double> edges, detail, area;
};

// The frame whose tile t is pattern choice[t]'s output.
torch::Tensor compose(const TiledFrame& f, const std::vector<int>& choice, int64_t tile) {
  torch::Tensor out = f.outputs[0].clone();
  for (size_t t = 0; t < f.tiles.size(); ++t) {
    const auto [y, x] = f.tiles[t];
    const int64_t h = std::min(tile, out.size(2) - y), w = std::min(tile, out.size(3) - x);
    out.narrow(2, y, h).narrow(3, x, w).copy_(f.outputs[choice[t]].narrow(2, y, h).narrow(3, x, w));
  }
  return out;
}

// Mean PSNR and cost over the frames when frame i's tiles take choices[i].
Point score(const std::vector<TiledFrame>& frames, const std::vector<std::vector<int>>& choices,
            const std::vector<double>& latency, int64_t tile, const QualityOptions& quality) {
  Point p;
  for (size_t i = 0; i < frames.size(); ++i) {
    const TiledFrame& f = frames[i];
    p.psnr += psnr(compose(f, choices[i], tile), f.hr, quality).item<double>();
    for (size_t t = 0; t < f.tiles.size(); ++t) p.cost += f.area[t] * latency[choices[i][t]];  // areas sum to 1
  }
  p.psnr /= frames.size();
  p.cost /= frames.size();
  return p;
}

// The best PSNR among `points` at a cost of at most `cost` (NAN when none is that cheap).
double best_within(const std::vector<Point>& points, double cost) {
  double best = NAN;
  for (const Point& p : points)
    if (p.cost <= cost * (1 + 1e-9) && !(p.psnr <= best)) best = p.psnr;
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  int threads = 0;
  int64_t tile_lr = 40;
  std::string model_path, data_path;
  EvalOptions eval;
  CLI::App app{"The bound on choosing a hybrid's pattern per tile instead of per frame"};
  app.add_option("--model", model_path, "a hybrid-pruned model (cgsr prune's pruned.cgsr)")->required();
  app.add_option("--data", data_path, "the data set")->required();
  app.add_option("--split", eval.split, "the split to evaluate")->capture_default_str();
  app.add_option("--frames", eval.frames, "frames of the split, A:B (all when empty)");
  app.add_option("--tile", tile_lr, "tile side, LR pixels")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--threads", threads, "LibTorch and TBB threads (0 = all hardware threads)")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  set_threads(threads);
  torch::NoGradGuard no_grad;
  const Dataset data = Dataset::open(data_path);
  const HybridModel model = load_hybrid_model(model_path);
  const int scale = model.network->spec().scale;
  const int64_t tile = tile_lr * scale;
  const std::vector<double>& latency = model.latency.median_ms;
  PatternNetworks patterns(*model.network, model.pool);
  const int K = patterns.size();
  if (static_cast<int>(latency.size()) != K) throw std::runtime_error(model_path + ": no latency per pattern");
  std::vector<RenderChannel> channels = model.network->input_channels();
  if (std::find(channels.begin(), channels.end(), RenderChannel::Edge) == channels.end())
    channels.push_back(RenderChannel::Edge);

  QualityOptions quality;
  quality.crop_border = eval.crop_border;
  quality.y_channel = eval.y_channel;
  std::vector<TiledFrame> frames;
  for (int index : evaluation_frames(data, eval)) {
    const Batch b = frame_batch(data, index, scale, channels, model.network->depth_encoding());
    TiledFrame f;
    f.hr = b.hr_color;
    const torch::Tensor info = model.network->info_input(b);
    for (int k = 0; k < K; ++k) f.outputs.push_back(patterns.run(k, b.lr_color, info).clamp(0, 1));
    const int64_t H = f.hr.size(2), W = f.hr.size(3);
    const torch::Tensor edge =
        pick_channels(b.hr_info, b.channels, {RenderChannel::Edge}, "hr_info", "bench")[0].reshape({H, W});
    // |d/dx| + |d/dy| of the LR colour, padded back to the LR size.
    const torch::Tensor lr = b.lr_color;
    const torch::Tensor gradient =
        torch::constant_pad_nd((lr.narrow(3, 1, lr.size(3) - 1) - lr.narrow(3, 0, lr.size(3) - 1)).abs(), {0, 1}) +
        torch::constant_pad_nd((lr.narrow(2, 1, lr.size(2) - 1) - lr.narrow(2, 0, lr.size(2) - 1)).abs(), {0, 0, 0, 1});
    for (int64_t y = 0; y < H; y += tile)
      for (int64_t x = 0; x < W; x += tile) {
        const int64_t h = std::min(tile, H - y), w = std::min(tile, W - x);
        f.tiles.push_back({y, x});
        f.area.push_back(static_cast<double>(h * w) / static_cast<double>(H * W));
        f.edges.push_back(edge.narrow(0, y, h).narrow(1, x, w).gt(0).to(torch::kFloat).mean().item<double>());
        f.detail.push_back(gradient.narrow(2, y / scale, std::max<int64_t>(1, h / scale))
                               .narrow(3, x / scale, std::max<int64_t>(1, w / scale))
                               .mean()
                               .item<double>());
      }
    f.sse.assign(K, {});
    for (int k = 0; k < K; ++k)
      for (const auto& [y, x] : f.tiles) {
        const int64_t h = std::min(tile, H - y), w = std::min(tile, W - x);
        f.sse[k].push_back((f.outputs[k].narrow(2, y, h).narrow(3, x, w) - f.hr.narrow(2, y, h).narrow(3, x, w))
                               .square()
                               .sum()
                               .item<double>());
      }
    frames.push_back(std::move(f));
  }

  // Lagrangian sweep: lambda in squared-error units per ms of a whole frame.
  const auto lagrangian = [&](bool per_tile) {
    std::vector<Point> points;
    for (double lambda = 1e-3; lambda < 1e4; lambda *= 1.15) {
      std::vector<std::vector<int>> choices;
      for (const TiledFrame& f : frames) {
        const size_t T = f.tiles.size();
        std::vector<int> c(T, 0);
        if (per_tile) {
          for (size_t t = 0; t < T; ++t) {
            double best = INFINITY;
            for (int k = 0; k < K; ++k) {
              const double v = f.sse[k][t] + lambda * latency[k] * f.area[t];
              if (v < best) best = v, c[t] = k;
            }
          }
        } else {
          double best = INFINITY;
          int pick = 0;
          for (int k = 0; k < K; ++k) {
            double v = lambda * latency[k];
            for (size_t t = 0; t < T; ++t) v += f.sse[k][t];
            if (v < best) best = v, pick = k;
          }
          std::fill(c.begin(), c.end(), pick);
        }
        choices.push_back(std::move(c));
      }
      points.push_back(score(frames, choices, latency, tile, quality));
    }
    return points;
  };
  const std::vector<Point> oracle_tile = lagrangian(true), oracle_frame = lagrangian(false);

  // Every pair of patterns, the share of tiles ranked highest by `rank` taking the wider one.
  const auto by_rank = [&](std::vector<double> TiledFrame::*rank) {
    std::vector<Point> points;
    for (int wide = 0; wide < K; ++wide)
      for (int narrow = wide + 1; narrow < K; ++narrow)
        for (int share = 0; share <= 20; ++share) {
          std::vector<std::vector<int>> choices;
          for (const TiledFrame& f : frames) {
            const std::vector<double>& r = f.*rank;
            std::vector<size_t> order(r.size());
            for (size_t t = 0; t < order.size(); ++t) order[t] = t;
            std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return r[a] > r[b]; });
            std::vector<int> c(order.size(), narrow);
            for (size_t i = 0; i < order.size() * share / 20; ++i) c[order[i]] = wide;
            choices.push_back(std::move(c));
          }
          points.push_back(score(frames, choices, latency, tile, quality));
        }
    return points;
  };
  const std::vector<Point> by_edges = by_rank(&TiledFrame::edges), by_detail = by_rank(&TiledFrame::detail);

  std::printf("%s on %s (%s, %zu frames), tiles of %lld LR pixels, %d threads\n", model_path.c_str(),
              data_path.c_str(), eval.split.c_str(), frames.size(), static_cast<long long>(tile_lr), thread_count());
  std::printf("%-8s %9s %9s %15s %14s %15s %16s\n", "pattern", "ms", "PSNR dB", "oracle/tile dB", "edges/tile dB",
              "detail/tile dB", "oracle/frame dB");
  for (int k = 0; k < K; ++k) {
    std::vector<std::vector<int>> alone;
    for (const TiledFrame& f : frames) alone.emplace_back(f.tiles.size(), k);
    const Point p = score(frames, alone, latency, tile, quality);
    std::printf("%-8d %9.2f %9.3f %15.3f %14.3f %15.3f %16.3f\n", k, p.cost, p.psnr,
                best_within(oracle_tile, p.cost) - p.psnr, best_within(by_edges, p.cost) - p.psnr,
                best_within(by_detail, p.cost) - p.psnr, best_within(oracle_frame, p.cost) - p.psnr);
  }
  std::printf("(the choosers' columns: their best PSNR at no more than the pattern's cost, minus the pattern's)\n");
  return 0;
}
