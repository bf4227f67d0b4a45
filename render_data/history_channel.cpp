#include "render_data/history_channel.h"

#include <oneapi/tbb/parallel_for.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/tensor_checks.h"

namespace cgsr {

bool same_surface_depth(float a, float b, double tolerance) {
  const bool sky_a = std::isinf(a), sky_b = std::isinf(b);
  if (sky_a || sky_b) return sky_a && sky_b;
  return std::abs(a - b) <= tolerance * std::min(a, b);
}

bool history_link_holds(float older, float newer, const HistoryDepthTest& test) {
  const bool sky_older = std::isinf(older), sky_newer = std::isinf(newer);
  if (sky_older || sky_newer) return sky_older && sky_newer;
  return older >= newer * (1 - test.link_nearer) && older <= newer * (1 + test.link_farther);
}

namespace {

// A frame's tensors as contiguous float32, checked against the sizes they must have.
struct Planes {
  torch::Tensor color, lr_depth, depth, motion;
  const float *c = nullptr, *ld = nullptr, *d = nullptr, *m = nullptr;
};

torch::Tensor checked(const torch::Tensor& t, int64_t channels, int64_t h, int64_t w, const std::string& what,
                      const std::string& name) {
  if (!t.defined()) throw Error(what, "needs " + name + ", which the frame does not have");
  if (t.dim() != 3 || t.size(0) != channels || t.size(1) != h || t.size(2) != w)
    throw Error(what, name + " must be [" + std::to_string(channels) + ", " + std::to_string(h) + ", " +
                          std::to_string(w) + "], got " + shape_string(t));
  return t.to(torch::kFloat32).contiguous();
}

}  // namespace

torch::Tensor history_out_channel(const torch::Tensor& depth, const torch::Tensor& motion,
                                  const torch::Tensor& previous_depth, const std::string& what,
                                  const HistoryDepthTest& depth_test) {
  if (!depth.defined()) throw Error(what, "the history_out channel needs depth, which the frame does not have");
  const int64_t h = depth.size(-2), w = depth.size(-1);
  const auto d = checked(depth, 1, h, w, what, "depth");
  const auto m = checked(motion, 2, h, w, what, "motion");
  auto out = torch::zeros({6, h, w}, torch::kFloat32);
  out.narrow(0, 4, 2).copy_(m);
  if (!previous_depth.defined()) return out;
  const auto p = checked(previous_depth, 1, h, w, what, "the previous frame's depth");
  const float *dd = d.data_ptr<float>(), *mm = m.data_ptr<float>(), *pd = p.data_ptr<float>();
  float* valid = out[3].data_ptr<float>();
  const int64_t n = h * w;
  tbb::parallel_for(int64_t(0), h, [&](int64_t y) {
    for (int64_t x = 0; x < w; ++x) {
      const int64_t i = y * w + x;
      if (std::isinf(dd[i])) continue;
      const double qx = x + 0.5 + mm[i], qy = y + 0.5 + mm[n + i];
      if (!(qx >= 0 && qx < w && qy >= 0 && qy < h)) continue;
      const float older = pd[static_cast<int64_t>(qy) * w + static_cast<int64_t>(qx)];
      valid[i] = history_link_holds(older, dd[i], depth_test) ? 1.0f : 0.0f;
    }
  });
  return out;
}

namespace {
// Where history_out starts in an info tensor of `channels`; -1 without it.
int64_t history_out_offset(const std::vector<RenderChannel>& channels) {
  int64_t offset = 0;
  for (auto c : channels) {
    if (c == RenderChannel::HistoryOut) return offset;
    offset += channel_width(c);
  }
  return -1;
}
}  // namespace

bool reads_previous_output(const std::vector<RenderChannel>& channels) { return history_out_offset(channels) >= 0; }

torch::Tensor with_previous_output(const torch::Tensor& info, const std::vector<RenderChannel>& channels,
                                   const torch::Tensor& previous) {
  const int64_t offset = history_out_offset(channels);
  if (offset < 0) return info;
  if (!previous.defined()) {
    auto out = info.clone();
    out.select(1, offset + 3).zero_();
    return out;
  }
  if (previous.dim() != 4 || previous.size(1) != 3 || previous.size(0) != info.size(0) ||
      previous.size(2) != info.size(2) || previous.size(3) != info.size(3))
    throw Error("history_out", "the previous output must be [" + std::to_string(info.size(0)) + ", 3, " +
                                   std::to_string(info.size(2)) + ", " + std::to_string(info.size(3)) + "], got " +
                                   shape_string(previous));
  return torch::cat({info.narrow(1, 0, offset), previous.clamp(0, 1).to(info.scalar_type()),
                     info.narrow(1, offset + 3, info.size(1) - offset - 3)},
                    1);
}

void restrict_history_out_to_window(torch::Tensor& info, const std::vector<RenderChannel>& channels) {
  const int64_t offset = history_out_offset(channels);
  if (offset < 0) return;
  const int64_t h = info.size(-2), w = info.size(-1);
  const auto x = torch::arange(w, torch::kFloat32).add_(0.5).view({1, w}) + info[offset + 4];
  const auto y = torch::arange(h, torch::kFloat32).add_(0.5).view({h, 1}) + info[offset + 5];
  const auto inside = (x >= 0).logical_and_(x < w).logical_and_(y >= 0).logical_and_(y < h);
  info[offset + 3].mul_(inside.to(torch::kFloat32));
}

torch::Tensor history_channel(const std::vector<HistoryFrame>& frames, int scale, const std::string& what,
                              const HistoryDepthTest& depth_test) {
  if (frames.empty()) throw Error(what, "the history channel needs the current frame");
  if (frames.size() > static_cast<size_t>(kHistoryFrames) + 1)
    throw Error(what, "the history channel gathers at most " + std::to_string(kHistoryFrames + 1) + " frames, got " +
                          std::to_string(frames.size()));
  if (scale < 1) throw Error(what, "scale must be >= 1, got " + std::to_string(scale));
  const auto& c0 = frames[0].lr_color;
  if (!c0.defined() || c0.dim() != 3) throw Error(what, "the LR colour must be [3,h,w], got " + shape_string(c0));
  const int64_t h = c0.size(1), w = c0.size(2), H = h * scale, W = w * scale;
  const size_t n = frames.size();
  std::vector<Planes> p(n);
  for (size_t k = 0; k < n; ++k) {
    const HistoryFrame& f = frames[k];
    const std::string at = what + " (frame t-" + std::to_string(k) + ")";
    p[k].color = checked(f.lr_color, 3, h, w, at, "LR colour");
    if (f.lr_color.scalar_type() == torch::kUInt8) p[k].color = p[k].color / 255.0f;
    p[k].lr_depth = checked(f.lr_depth, 1, h, w, at, "LR depth");
    // Depth at r: the current frame's and every link's but the last one's (which compares with the previous link).
    if (k == 0 || f.depth.defined()) p[k].depth = checked(f.depth, 1, H, W, at, "depth at the history's resolution");
    // Motion leads to the next older frame: needed where there is one.
    if (k + 1 < n) p[k].motion = checked(f.motion, 2, H, W, at, "motion at the history's resolution");
    p[k].c = p[k].color.data_ptr<float>();
    p[k].ld = p[k].lr_depth.data_ptr<float>();
    p[k].d = p[k].depth.defined() ? p[k].depth.data_ptr<float>() : nullptr;
    p[k].m = p[k].motion.defined() ? p[k].motion.data_ptr<float>() : nullptr;
  }
  torch::Tensor out = torch::zeros({4, H, W}, torch::kFloat32);
  float* o = out.data_ptr<float>();
  const int64_t plane = H * W, lr_plane = h * w;
  tbb::parallel_for(int64_t{0}, H, [&](int64_t i) {
    for (int64_t j = 0; j < W; ++j) {
      double qx = j + 0.5, qy = i + 0.5;
      float ref = p[0].d[i * W + j];  // the point's depth in the latest frame of the chain
      for (size_t k = 0; k < n; ++k) {
        if (k > 0) {
          // One link back: frame t-k+1's motion at the r-pixel containing the position.
          const int64_t at = static_cast<int64_t>(std::floor(qy)) * W + static_cast<int64_t>(std::floor(qx));
          qx += p[k - 1].m[at];
          qy += p[k - 1].m[plane + at];
          if (!(qx >= 0 && qx < W && qy >= 0 && qy < H)) break;  // left the image (or NaN motion)
          if (p[k].d) {
            const float here = p[k].d[static_cast<int64_t>(std::floor(qy)) * W + static_cast<int64_t>(std::floor(qx))];
            if (!history_link_holds(here, ref, depth_test)) break;  // hidden in this frame, or lost
            ref = here;
          }
        }
        // Frame t-k's nearest sample: LR pixel x sampled r-position scale * (x + 0.5 - jitter).
        const double jx = frames[k].jitter[0], jy = frames[k].jitter[1];
        const int64_t x = static_cast<int64_t>(std::floor(qx / scale + jx));
        const int64_t y = static_cast<int64_t>(std::floor(qy / scale + jy));
        if (x < 0 || x >= w || y < 0 || y >= h) continue;
        if (std::abs(scale * (x + 0.5 - jx) - qx) > 0.5 || std::abs(scale * (y + 0.5 - jy) - qy) > 0.5) continue;
        const int64_t s = y * w + x;
        if (!same_surface_depth(p[k].ld[s], ref, depth_test.sample)) continue;
        const int64_t to = i * W + j;
        for (int c = 0; c < 3; ++c) o[c * plane + to] = p[k].c[c * lr_plane + s];
        o[3 * plane + to] = 1.0f - static_cast<float>(k) / (kHistoryFrames + 1);
        break;
      }
    }
  });
  return out;
}

}  // namespace cgsr
