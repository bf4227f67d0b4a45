#include "render_data/bsp_border_builder.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "core/config.h"
#include "core/error.h"
#include "core/image_header.h"

namespace cgsr {
namespace {

// How mixed `region` is: the samples not of its most frequent surface, and the Gini impurity
// scaled by the region's size (n - sum of squared counts / n), which also falls for a split that
// only prepares the next one (a corner: one line leaves as many samples on the wrong side, two
// lines none).
struct Mix {
  int wrong = 0;
  double gini = 0;
};
Mix mix(const std::vector<BspSample>& samples, const std::vector<int>& region) {
  std::map<int32_t, int> count;  // ordered: deterministic
  int best = 0;
  for (int i : region) best = std::max(best, ++count[samples[i].surface]);
  double squares = 0;
  for (const auto& [surface, c] : count) squares += static_cast<double>(c) * c;
  const double n = static_cast<double>(region.size());
  return {static_cast<int>(region.size()) - best, n > 0 ? n - squares / n : 0.0};
}

Rgb8 mean_color(const std::vector<BspSample>& samples, const std::vector<int>& region) {
  const bool any_own = std::any_of(region.begin(), region.end(), [&](int i) { return samples[i].own; });
  double sum[3] = {0, 0, 0};
  int n = 0;
  for (int i : region)
    if (samples[i].own || !any_own) {
      for (int c = 0; c < 3; ++c) sum[c] += samples[i].color[c];
      ++n;
    }
  Rgb8 out;
  for (int c = 0; c < 3; ++c) {
    const double v = std::clamp(sum[c] / static_cast<double>(n), 0.0, 1.0);
    out[c] = static_cast<uint8_t>(std::lround(v * 255.0));
  }
  return out;
}

struct Builder {
  const std::vector<BspSample>& samples;
  const std::vector<BspCandidate>& candidates;
  int max_depth;
  BspTree tree;
  int node = 0;  // next preorder node

  void build(const std::vector<int>& region, int depth) {
    const Mix here = mix(samples, region);
    int best = -1;
    Mix best_mix = here;
    std::vector<int> best_pos, best_neg;
    if (here.wrong > 0 && depth < max_depth) {
      std::vector<int> pos, neg;
      for (size_t k = 0; k < candidates.size(); ++k) {
        pos.clear();
        neg.clear();
        for (int i : region) (candidates[k].line.side(samples[i].x, samples[i].y) >= 0 ? pos : neg).push_back(i);
        if (pos.empty() || neg.empty()) continue;
        const Mix a = mix(samples, pos), b = mix(samples, neg);
        const Mix split{a.wrong + b.wrong, a.gini + b.gini};
        // Fewest samples on the wrong side first, then the lowest Gini; a split must lower the Gini.
        constexpr double kEps = 1e-9;
        const bool better =
            best < 0 ? split.gini < here.gini - kEps
                     : split.wrong < best_mix.wrong ||
                           (split.wrong == best_mix.wrong &&
                            (split.gini < best_mix.gini - kEps ||
                             (split.gini <= best_mix.gini + kEps && candidates[k].priority < candidates[best].priority)));
        if (better) {
          best = static_cast<int>(k);
          best_mix = split;
          best_pos = pos;
          best_neg = neg;
        }
      }
    }
    const int me = node++;
    if (best < 0) {
      tree.leaves.push_back(mean_color(samples, region));
      return;
    }
    tree.shape |= 1u << me;
    tree.lines.push_back(candidates[best].line);
    build(best_pos, depth + 1);
    build(best_neg, depth + 1);
  }
};

}  // namespace

void check_bsp_border_settings(const BspBorderSettings& settings, int width, int height) {
  if (settings.depth < 1 || settings.depth > kMaxBspDepth)
    throw Error("bsp_border", "depth " + config::out_of_range(settings.depth, 1, kMaxBspDepth));
  if (settings.samples < 2 || settings.samples > 16)
    throw Error("bsp_border", "samples " + config::out_of_range(settings.samples, 2, 16));
  if (width <= 0 || height <= 0) throw Error("bsp_border", "image size must be positive");
  // The supersampled visibility buffer is the pass's memory: bounded like any image cgsr renders.
  const int64_t m = settings.samples, w = int64_t{width} * m, h = int64_t{height} * m;
  if (w > kMaxImageSide || h > kMaxImageSide || w * h > kMaxImagePixels)
    throw Error("bsp_border", "samples " + std::to_string(m) + " at " + std::to_string(width) + "x" +
                                  std::to_string(height) + " rasterizes " + std::to_string(w) + "x" + std::to_string(h) +
                                  " samples, more than cgsr renders (" + std::to_string(kMaxImageSide) + " per side, " +
                                  std::to_string(kMaxImagePixels) + " in all); use fewer samples");
}

std::optional<BspLine> line_through(double x0, double y0, double x1, double y1) {
  const double a = y0 - y1, b = x1 - x0;
  const double n = std::hypot(a, b);
  if (!(n > 0) || !std::isfinite(n)) return std::nullopt;
  BspLine l;
  l.a = static_cast<float>(a / n);
  l.b = static_cast<float>(b / n);
  // c from the rounded a and b, so the stored line passes through the midpoint as exactly as floats allow.
  l.c = static_cast<float>(-(static_cast<double>(l.a) * (x0 + x1) * 0.5 + static_cast<double>(l.b) * (y0 + y1) * 0.5));
  return l;
}

std::optional<BspTree> build_pixel_bsp(const std::vector<BspSample>& samples, const std::vector<BspCandidate>& candidates,
                                       int max_depth) {
  if (samples.empty() || max_depth < 1) return std::nullopt;
  std::vector<int> all(samples.size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int>(i);
  Builder b{samples, candidates, std::min(max_depth, kMaxBspDepth), {}};
  b.build(all, 0);
  if (b.tree.lines.empty()) return std::nullopt;
  return b.tree;
}

}  // namespace cgsr
